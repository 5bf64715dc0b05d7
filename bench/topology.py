#!/usr/bin/python3
"""Sub-pixel topology of watermesh against the exact union (issue 12).

    /usr/bin/python3 bench/topology.py [--seeds 50] [--first-seed 0]
        [--families wedge,parallel,island,subpixel,seam]
        [--option KEY=VALUE]... [--build DIR] [--cli] [--json out.json]
        [--worst 3] [--keep DIR] [--densify PX]

For each family of autotest/adversarial.py and each seed, writes the scene,
runs watermesh on it (in this process through the GDAL driver, or with
--cli through <build>/gdal_watermesh, which survives a crash of the
driver) with SIMPLIFY=0, METHOD=CONTOUR, NUM_THREADS=1 (then every
--option, which may override them; PIXEL_SIZE / BLOCK_SIZE also scale the
scenes; --densify PX puts a vertex every PX pixels along every river and
lake edge of the scene first, snapped to the lattice: adversarial.densify),
computes the GEOS oracle (autotest/oracle.py: exact buffer and
dissolve, clipped to the blocks) and prints one Markdown table, a row per
family:

  H max        boundary Hausdorff distance (px), worst scene (each block's
               square counts as boundary of both, as in oracle.compare;
               boundaries sampled every min(0.1 m, px / 10))
  H p99        99th percentile of all the family's boundary sample
               distances (px), both directions pooled over its scenes
  >0.5px       scenes whose Hausdorff distance exceeds 0.5 px
  vertex off   farthest output vertex from its own block's clipped exact
               boundary (px), the block square counting only where the
               exact water is cut by it (adversarial.vertex_offset: a spike
               along a block side, which H counts as near the boundary)
  specks       output rings (outer / hole) whose vertices all lie within
               0.5 px of each other (max pairwise distance), touching a side
               of their block or not, and for which the oracle has no ring of
               the same kind within 1 px that is that small too (diameter
               <= the speck's + 1 px: what a ring within 0.5 px of it may
               measure): tiny rings the exact union does not have; not
               within 1 px of a pinch point (where pieces of the exact union
               meet at a point, the output may give a piece its own ring)
  lost         oracle rings touching no block side, bounding box under 2 px
               (both sides), with no output ring of the same kind within
               1 px (of any kind for a ring with a pinch point: a lens may
               be joined to the water it touches): small islands and lakes
               that vanished; "/ small": how many such small oracle rings
               the scenes have. An oracle ring shorter than two lattice
               units (px / 128) both ways is below the lattice: excused
               from being kept, from this count and from the oracle's side
               of H (adversarial.resolvable), not from justifying an output
               ring there
  pinched      oracle rings with a pinch point (touching another ring or
               themselves at a point: the even-odd parts of an invalid lake
               whose holes overlap), so excused as above
  ring diff    sum over blocks and ring kinds of |output rings - oracle
               rings| (dashed rivers, rows of holes, merged strips; the
               oracle's rings below the lattice left out)
  symdiff      area of the symmetric difference with the oracle, m², summed
               over the family's scenes (and relative to their oracle area)
  area max     largest |area - oracle area| / oracle area over the scenes
               whose oracle area exceeds 100 m² (%)
  invalid      output polygons that are not valid (shapely)
  seams        T-junctions + gaps on shared block sides (oracle.check_seams)
  errors       runs that failed (no dataset, exception, CLI exit status)
  s/scene      mean seconds per scene: driver run / oracle + checks

After the table: per family the worst seeds (by Hausdorff, then specks,
lost features), every seed with an invalid polygon, a seam defect or an
error, each with the scene's parameters (adversarial.describe) so it can be
reproduced: `make_scene(path, family, seed)`. --json writes every scene's
figures. --keep DIR keeps the scenes (and --cli outputs) in DIR.
"""

import argparse
import faulthandler
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
AUTOTEST = os.path.join(REPO, 'autotest')

AREA_MIN_M2 = 100.0   # area column: scenes with more oracle water than this


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--seeds', type=int, default=50, help='seeds per family (default 50)')
    ap.add_argument('--first-seed', type=int, default=0, help='first seed (default 0)')
    ap.add_argument('--families', default=None,
                    help='comma-separated families (default: all)')
    ap.add_argument('--option', action='append', default=[], metavar='KEY=VALUE',
                    help='driver open option (repeatable), after the defaults '
                         'SIMPLIFY=0 METHOD=CONTOUR NUM_THREADS=1')
    ap.add_argument('--build', default=REPO,
                    help='build directory: the newer of .libs/gdal_WATERMESH.so and '
                         'plugins/gdal_WATERMESH.so, and gdal_watermesh (default: %(default)s)')
    ap.add_argument('--cli', action='store_true',
                    help='run <build>/gdal_watermesh in a subprocess per scene')
    ap.add_argument('--json', default=None, help='write the per-scene figures there')
    ap.add_argument('--worst', type=int, default=3, help='worst seeds listed per family')
    ap.add_argument('--keep', default=None, help='keep the scenes in this folder')
    ap.add_argument('--densify', type=float, default=0, metavar='PX',
                    help='a vertex every PX pixels along the inputs (default: none)')
    args = ap.parse_args(argv)
    opts = {}
    for o in args.option:
        if '=' not in o:
            ap.error('--option wants KEY=VALUE, got %r' % o)
        k, v = o.split('=', 1)
        opts[k.strip().upper()] = v
    args.options = opts
    args.build = os.path.abspath(args.build)
    return args


def setup_driver(build, tmp):
    """GDAL_DRIVER_PATH for `build` (set before osgeo is imported): its
    plugins/ folder (what make check fills), or a copy of
    .libs/gdal_WATERMESH.so when that is missing or older than .libs'."""
    plugin = os.path.join(build, 'plugins', 'gdal_WATERMESH.so')
    libs_so = os.path.join(build, '.libs', 'gdal_WATERMESH.so')
    if os.path.exists(libs_so) and (not os.path.exists(plugin) or
                                    os.path.getmtime(libs_so) > os.path.getmtime(plugin) + 1):
        d = os.path.join(tmp, 'plugins')
        os.makedirs(d, exist_ok=True)
        shutil.copy2(libs_so, d)
        return d
    if os.path.exists(plugin):
        return os.path.dirname(plugin)
    sys.exit('no gdal_WATERMESH.so in %s/plugins or %s/.libs: build it first' % (build, build))


def read_water(ds_or_path):
    import oracle
    from osgeo import gdal
    from shapely import wkb as swkb
    ds = ds_or_path
    if isinstance(ds, str):
        ds = gdal.OpenEx(ds, gdal.OF_VECTOR)
    lyr = ds.GetLayerByName('water')
    out = []
    lyr.ResetReading()
    for f in lyr:
        g = f.GetGeometryRef()
        if g is None or g.IsEmpty():
            continue
        wkb = bytes(g.ExportToIsoWkb())
        fields = {'block_x': f.GetField('block_x'), 'block_y': f.GetField('block_y')}
        if f.GetDefnRef().GetFieldIndex('area') >= 0:
            fields['area'] = f.GetField('area')
        out.append(oracle.Feat((fields['block_x'], fields['block_y']), swkb.loads(wkb), wkb, fields))
    return out


def run_driver(options, args, workdir, tag):
    """Water features of one run, or raises RuntimeError."""
    from osgeo import gdal
    if args.cli:
        exe = os.path.join(args.build, 'gdal_watermesh')
        out = os.path.join(workdir, tag + '.out.gpkg')
        if os.path.exists(out):
            os.unlink(out)
        cmd = [exe, '-q']
        for k, v in options.items():
            cmd += ['-' + k.lower(), str(v)]
        cmd.append(out)
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True, timeout=300)
        if p.returncode != 0:
            raise RuntimeError('exit status %d: %s' % (p.returncode, (p.stderr or p.stdout).strip()[-300:]))
        return read_water(out)
    msgs = []
    gdal.PushErrorHandler(lambda c, n, m: msgs.append(m) if c >= gdal.CE_Failure else None)
    try:
        ds = gdal.OpenEx('WATERMESH:', gdal.OF_VECTOR, allowed_drivers=['WATERMESH'],
                         open_options=['%s=%s' % (k, v) for k, v in options.items()])
        if ds is None:
            raise RuntimeError('open failed: %s' % ('; '.join(msgs) or gdal.GetLastErrorMsg()))
        water = read_water(ds)
        ds = None
        if msgs:
            raise RuntimeError('errors: %s' % '; '.join(msgs))
        return water
    finally:
        gdal.PopErrorHandler()


def measure_scene(family, seed, args, workdir, px, B):
    """(figures, boundary distances in px or None on error) of one scene."""
    import adversarial
    import oracle
    from osgeo import gdal
    tag = '%s_%d' % (family, seed)
    path = os.path.join(workdir, tag + '.gpkg')
    opts = adversarial.make_scene(path, family, seed, pixel_size=px, block_size=B)
    if args.densify > 0:
        adversarial.densify(path, args.densify, px)
    opts.update({'SIMPLIFY': 0, 'METHOD': 'CONTOUR', 'NUM_THREADS': 1})
    opts.update(args.options)
    rec = dict(family=family, seed=seed)
    t = time.time()
    try:
        water = run_driver(opts, args, workdir, tag)
    except Exception as e:  # noqa: BLE001 - reported per scene
        rec.update(error=str(e), run_s=time.time() - t)
        return rec, None
    rec['run_s'] = time.time() - t
    t = time.time()
    orc = oracle.oracle_blocks(oracle.inputs_from_options(opts), B)
    tj, gaps, _ = oracle.check_seams(water, B)
    rec['seams'] = tj + gaps
    gdal.PushErrorHandler('CPLQuietErrorHandler')
    try:
        fig, d = adversarial.measure(water, orc, B, px)
    finally:
        gdal.PopErrorHandler()
    rec.update(fig)
    rec['check_s'] = time.time() - t
    return rec, d


# ----------------------------------------------------------------------------
# table
# ----------------------------------------------------------------------------

def family_row(family, recs, dists):
    import numpy as np
    ok = [r for r in recs if 'error' not in r]
    pooled = np.concatenate(dists) if dists else np.zeros(0)
    big = [r for r in ok if r['oracle_area_m2'] > AREA_MIN_M2]
    oa = sum(r['oracle_area_m2'] for r in ok)
    sd = sum(r['symdiff_m2'] for r in ok)
    so, sh = sum(r['specks_outer'] for r in ok), sum(r['specks_hole'] for r in ok)
    lo, lh = sum(r['lost_outer'] for r in ok), sum(r['lost_hole'] for r in ok)
    smo, smh = sum(r['small_outer'] for r in ok), sum(r['small_hole'] for r in ok)
    return [family, str(len(recs)),
            '%.2f' % max([r['hausdorff_px'] for r in ok] or [0.0]),
            '%.3f' % (float(np.percentile(pooled, 99)) if len(pooled) else 0.0),
            str(sum(r['hausdorff_px'] > 0.5 for r in ok)),
            '%.2f' % max([r['vertex_off_px'] for r in ok] or [0.0]),
            '%d (%d / %d)' % (so + sh, so, sh),
            '%d / %d (%d / %d)' % (lo + lh, smo + smh, lo, lh),
            str(sum(r['ring_diff'] for r in ok)),
            str(sum(r.get('pinched', 0) for r in ok)),
            '%.2f (%.3f %%)' % (sd, 100.0 * sd / oa if oa else 0.0),
            '%.3f' % (100.0 * max([abs(r['rel_area_diff']) for r in big] or [0.0])),
            str(sum(r['invalid'] for r in ok)),
            str(sum(r['seams'] for r in ok)),
            str(len(recs) - len(ok)),
            '%.3f / %.3f' % (sum(r['run_s'] for r in recs) / max(1, len(recs)),
                             sum(r.get('check_s', 0.0) for r in ok) / max(1, len(ok)))]


HEADER = ['family', 'scenes', 'H max px', 'H p99 px', '>0.5px', 'vertex off px',
          'specks (outer / hole)',
          'lost / small (lost outer / hole)', 'ring diff', 'pinched', 'symdiff m² (rel)', 'area max %',
          'invalid',
          'seams', 'errors', 's/scene run / check']


def markdown(rows):
    out = ['| ' + ' | '.join(HEADER) + ' |', '|' + '---|' * len(HEADER)]
    out += ['| ' + ' | '.join(r) + ' |' for r in rows]
    return '\n'.join(out)


def main(argv=None):
    args = parse_args(argv if argv is not None else sys.argv[1:])
    tmp = tempfile.mkdtemp(prefix='wm_topology_')
    try:
        os.environ['GDAL_DRIVER_PATH'] = setup_driver(args.build, tmp)
        faulthandler.enable()
        sys.path.insert(0, AUTOTEST)
        from osgeo import gdal
        gdal.AllRegister()
        if not args.cli and gdal.GetDriverByName('WATERMESH') is None:
            sys.exit('the WATERMESH driver did not register from %s' % os.environ['GDAL_DRIVER_PATH'])
        import adversarial
        fams = args.families.split(',') if args.families else list(adversarial.FAMILIES)
        for f in fams:
            if f not in adversarial.FAMILIES:
                sys.exit('unknown family %r (one of %s)' % (f, ', '.join(adversarial.FAMILIES)))
        px = float(args.options.get('PIXEL_SIZE', adversarial.PIXEL_SIZE))
        B = float(args.options.get('BLOCK_SIZE', adversarial.BLOCK_SIZE))
        workdir = args.keep or os.path.join(tmp, 'scenes')
        os.makedirs(workdir, exist_ok=True)
        seeds = range(args.first_seed, args.first_seed + args.seeds)
        shown = dict({'SIMPLIFY': 0, 'METHOD': 'CONTOUR', 'NUM_THREADS': 1}, **args.options)
        print('build %s%s (%s); options %s; seeds %d..%d; PIXEL_SIZE %g, BLOCK_SIZE %g%s\n'
              % (args.build, _commit(args.build), 'CLI' if args.cli else 'driver in process',
                 ' '.join('%s=%s' % kv for kv in sorted(shown.items())), seeds[0], seeds[-1], px, B,
                 '; inputs densified every %g px' % args.densify if args.densify > 0 else ''))
        sys.stdout.flush()
        tty = sys.stderr.isatty()
        rows, all_recs, notes = [], [], []
        t0 = time.time()
        for fam in fams:
            recs, dists = [], []
            for seed in seeds:
                if tty:
                    sys.stderr.write('\r%s seed %d   ' % (fam, seed))
                    sys.stderr.flush()
                rec, d = measure_scene(fam, seed, args, workdir, px, B)
                recs.append(rec)
                if d is not None:
                    dists.append(d)
            rows.append(family_row(fam, recs, dists))
            if not tty:
                print('%s: %d scenes, %.1f s' % (fam, len(recs), time.time() - t0), file=sys.stderr)
            all_recs += recs
            ok = [r for r in recs if 'error' not in r]
            worst = sorted(ok, key=lambda r: (-r['hausdorff_px'], -(r['specks_outer'] + r['specks_hole']),
                                              -(r['lost_outer'] + r['lost_hole'])))[:args.worst]
            for r in worst:
                notes.append('- worst %s: H %.2f px at %s, specks %d/%d, lost %d/%d, ring diff %d: %s'
                             % (fam, r['hausdorff_px'], _xy(r['worst_at']), r['specks_outer'],
                                r['specks_hole'], r['lost_outer'], r['lost_hole'], r['ring_diff'],
                                adversarial.describe(fam, r['seed'], px, B)))
            for r in recs:
                if 'error' in r:
                    notes.append('- ERROR %s: %s' % (adversarial.describe(fam, r['seed'], px, B), r['error']))
                elif r['invalid'] or r['seams']:
                    notes.append('- %s: %d invalid polygons, %d seam defects'
                                 % (adversarial.describe(fam, r['seed'], px, B), r['invalid'], r['seams']))
        sys.stderr.write('%sdone in %.1f s%s\n' % ('\r' if tty else '', time.time() - t0, ' ' * 20))
        print(markdown(rows))
        if notes:
            print()
            print('\n'.join(notes))
        if args.json:
            with open(args.json, 'w', encoding='utf-8') as f:
                json.dump(dict(build=args.build, options=args.options, px=px, block_size=B,
                               densify_px=args.densify,
                               seeds=[seeds[0], seeds[-1]], header=HEADER, rows=rows,
                               scenes=all_recs), f, indent=1, default=str)
        return 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _commit(build):
    """' at <commit>[ + changes in src/ apps/]' when build is a git work tree."""
    try:
        c = subprocess.run(['git', '-C', build, 'rev-parse', '--short', 'HEAD'], stdout=subprocess.PIPE,
                           stderr=subprocess.DEVNULL, universal_newlines=True, timeout=10)
        if c.returncode != 0:
            return ''
        d = subprocess.run(['git', '-C', build, 'status', '--porcelain', '--', 'src', 'apps', 'kernels'],
                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, universal_newlines=True,
                           timeout=10)
        return ' at %s%s' % (c.stdout.strip(), ' + uncommitted changes in src/apps/kernels'
                             if d.stdout.strip() else '')
    except (OSError, subprocess.SubprocessError):
        return ''


def _xy(p):
    return '(%.2f, %.2f)' % p if p else '-'


if __name__ == '__main__':
    sys.exit(main())
