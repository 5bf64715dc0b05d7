#!/bin/sh
# Quick start, step 1: installs what is missing (Debian 12, as root), builds
# watermesh, and meshes the bundled Andorra OpenStreetMap extract into
# out/andorra.gpkg with a picture of the mesh in out/andorra.png.
set -eu
cd "$(dirname "$0")"
PKGS="build-essential autoconf automake libtool pkg-config clang-format libgdal-dev gdal-bin
python3-gdal python3-pytest python3-shapely python3-numpy python3-matplotlib
ocl-icd-opencl-dev opencl-headers pocl-opencl-icd clinfo clang libclang-rt-14-dev
qgis python3-qgis parallel munge slurm-wlm"
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
# GDAL's OGR conformance program, test_ogrsf, which `make check` builds and
# runs on the driver: three files of Debian's gdal source package, of the
# installed libgdal's version (a deb-src entry for the archive apt already
# uses is added when there is none)
T=tools/test_ogrsf
if [ ! -f "$T/test_ogrsf.cpp" ]; then
  if ! grep -rqsE '^(Types:.*deb-src|deb-src )' /etc/apt/sources.list /etc/apt/sources.list.d/; then
    d=/etc/apt/sources.list.d
    cat "$d"/*.sources 2>/dev/null | sed 's/^Types: deb$/Types: deb-src/' >/tmp/wm-src.$$
    mv /tmp/wm-src.$$ "$d/watermesh-deb-src.sources"
    if [ -f /etc/apt/sources.list ]; then
      sed -n 's/^deb /deb-src /p' /etc/apt/sources.list >"$d/watermesh-deb-src.list"
    fi
    apt-get update -qq
  fi
  src=$(mktemp -d)
  chown _apt "$src" 2>/dev/null || true
  (cd "$src" && apt-get source -qq --download-only \
    "gdal=$(dpkg-query -W -f='${source:Version}' libgdal-dev)")
  mkdir -p "$T"
  tar -xJf "$src"/gdal_*.orig.tar.xz -C "$T" --no-same-owner --strip-components=2 --wildcards \
    '*/apps/test_ogrsf.cpp' '*/apps/commonutils.cpp' '*/apps/commonutils.h'
  rm -rf "$src"
fi
# the Khronos glTF validator (npm) for the tests of -of GLB, into tools/node
if [ ! -d tools/node/node_modules/gltf-validator ]; then
  if ! command -v npm >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends nodejs npm
  fi
  npm install --silent --no-audit --no-fund --prefix tools/node gltf-validator@2.0.0-dev.3.10
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
