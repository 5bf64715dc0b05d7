#!/bin/sh
# Quick start, step 1: installs what is missing (Debian 12, as root), builds
# watermesh, and meshes the bundled Andorra OpenStreetMap extract into
# out/andorra.gpkg with a picture of the mesh in out/andorra.png.
set -eu
cd "$(dirname "$0")"
PKGS="build-essential autoconf automake libtool pkg-config clang-format libgdal-dev gdal-bin
python3-gdal python3-pytest python3-shapely python3-numpy python3-matplotlib
ocl-icd-opencl-dev opencl-headers pocl-opencl-icd clinfo clang libclang-rt-14-dev"
missing=""
for p in $PKGS; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  echo "Installing:$missing"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  # shellcheck disable=SC2086
  apt-get install -y -qq --no-install-recommends $missing
fi
[ -x configure ] || autoreconf -fi
[ -f Makefile ] || ./configure ${CONFIGURE_FLAGS:-}
make -j"$(nproc)"
[ "${WM_BUILD_ONLY:-0}" = 1 ] && exit 0
mkdir -p out
./gdal_watermesh -overwrite -stats -progress \
  -rivers data/osm/osm_andorra_2023.gpkg -rivers_layer rivers \
  -lakes data/osm/osm_andorra_2023.gpkg -lakes_layer lakes \
  out/andorra.gpkg
/usr/bin/python3 tools/render_mesh.py out/andorra.gpkg out/andorra.png
echo "Wrote out/andorra.gpkg (layers water, mesh) and out/andorra.png"
