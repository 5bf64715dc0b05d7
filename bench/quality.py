#!/usr/bin/python3
"""Output quality of a water mesh, for gdal_watermesh's output and
geos_peer's alike (both write a layer ``water`` of per-block polygons with
the fields ``block_x`` and ``block_y``).

    /usr/bin/python3 bench/quality.py out.gpkg [--block-size 4096]
        [--scene scene.gpkg [--width-field width] [--blocks 6] [--step 0.1]]

Seam defects, on every edge shared by two blocks of the grid (a block
without polygons counts as a block with no water):
  - T-junctions: a polygon vertex on the shared edge that lies in the
    interior of the other block's polygon edge running along it, with no
    vertex of the other block there;
  - coverage mismatches (gaps/overlaps): pieces of the shared edge covered
    by water (a polygon edge running along it) on one side only: the two
    blocks disagree on where the water crosses. Across such a piece the
    water surface either has a crack (one side stopped short of the edge,
    e.g. a crossing vertex simplified away) or a shoreline that runs along
    the block edge on one side only (e.g. a shallow dry notch flattened
    onto the edge by the simplification).
Both are counted exactly (a vertex is on the edge when its coordinate equals
the edge's, vertices match when equal) and with a tolerance (default 1 mm:
vertices within it match, pieces shorter than it are ignored), so that
floating-point noise can be told from real defects.

Invalid polygons: shapely is_valid on every water polygon.

Fidelity (with --scene): on a deterministic sample of blocks (evenly spaced
among the blocks with water, sorted), the exact buffer-and-dissolve of the
scene (autotest/oracle.py: 64 segments per quarter circle, lakes made valid)
is clipped to each block and compared with the output's polygons of that
block: Hausdorff distance between the boundaries (sampled every --step m,
so it may be under-estimated by up to step / 2; exact distances), its 99th
percentile and the relative area difference.
"""

import argparse
import json
import os
import sys
from collections import defaultdict

import numpy as np
from osgeo import gdal, ogr
from shapely import wkb as shapely_wkb

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'autotest'))
import oracle  # noqa: E402

gdal.UseExceptions()


def read_water(path, blocks=None):
    """[(block, shapely polygon)] of the layer water; only `blocks` if given."""
    ds = ogr.Open(path)
    lyr = ds.GetLayerByName('water')
    out = []
    for f in lyr:
        b = (f.GetField('block_x'), f.GetField('block_y'))
        if blocks is not None and b not in blocks:
            continue
        g = f.GetGeometryRef()
        if g is None or g.IsEmpty():
            continue
        out.append((b, shapely_wkb.loads(bytes(g.ExportToWkb()))))
    return out


# ----------------------------------------------------------------------------
# seams
# ----------------------------------------------------------------------------

def _merge(intervals, tol):
    out = []
    for a, b in sorted(intervals):
        if out and a <= out[-1][1] + tol:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return out


def edge_data(water, block_size, tol):
    """{edge key: {side: (vertex positions, covered intervals)}}. Key
    ('v', i, j): the line x = i*B between blocks (i-1, j) and (i, j); ('h',
    i, j): y = j*B between (i, j-1) and (i, j). Side 'hi': the edge is the
    block's high edge (the block is (i-1, j) or (i, j-1)); 'lo': its low."""
    B = float(block_size)
    acc = defaultdict(lambda: defaultdict(lambda: ([], [])))
    for (bx, by), poly in water:
        rings = [np.asarray(poly.exterior.coords)] + [np.asarray(r.coords) for r in poly.interiors]
        for key, axis, line, side, lo in (
                (('v', bx, by), 0, bx * B, 'lo', by * B),
                (('v', bx + 1, by), 0, (bx + 1) * B, 'hi', by * B),
                (('h', bx, by), 1, by * B, 'lo', bx * B),
                (('h', bx, by + 1), 1, (by + 1) * B, 'hi', bx * B)):
            other = 1 - axis
            for c in rings:
                on = np.abs(c[:, axis] - line) <= tol
                if not on.any():
                    continue
                on &= (c[:, other] >= lo - tol) & (c[:, other] <= lo + B + tol)
                verts, ints = acc[key][side]
                # a closed ring repeats its first vertex: count it once
                verts.extend(c[:-1][on[:-1], other].tolist())
                both = np.nonzero(on[:-1] & on[1:])[0]
                if len(both):
                    a, b = c[both, other], c[both + 1, other]
                    ints.extend(zip(np.minimum(a, b).tolist(), np.maximum(a, b).tolist()))
    return acc


def _inside(intervals, x, tol):
    """x strictly inside one of the merged intervals (by more than tol)."""
    return any(lo + tol < x < hi - tol for lo, hi in intervals)


def _symdiff(a, b):
    """Pieces (lo, hi) covered by exactly one of two merged interval lists."""
    pts = sorted(set([x for i in a for x in i] + [x for i in b for x in i]))

    def cov(ints, x):
        return any(lo <= x <= hi for lo, hi in ints)
    return [(lo, hi) for lo, hi in zip(pts[:-1], pts[1:])
            if cov(a, 0.5 * (lo + hi)) != cov(b, 0.5 * (lo + hi))]


def seam_defects(water, block_size, tol=0.0):
    """(t_junctions, gap_pieces, gap_length_m) over all shared block edges."""
    ed = edge_data(water, block_size, tol)
    tj, gaps, gap_len = 0, 0, 0.0
    for key, sides in ed.items():
        va, ia = sides.get('hi', ([], []))
        vb, ib = sides.get('lo', ([], []))
        ma, mb = _merge(ia, tol), _merge(ib, tol)
        sa, sb = np.unique(va), np.unique(vb)
        for mine, theirs_v, theirs_i in ((sa, sb, mb), (sb, sa, ma)):
            for v in mine:
                if not _inside(theirs_i, v, tol):
                    continue
                k = np.searchsorted(theirs_v, v)
                near = [theirs_v[j] for j in (k - 1, k) if 0 <= j < len(theirs_v)]
                if not any(abs(v - w) <= tol for w in near):
                    tj += 1
        for lo, hi in _symdiff(ma, mb):
            if hi - lo > tol:
                gaps += 1
                gap_len += hi - lo
    return tj, gaps, gap_len


# ----------------------------------------------------------------------------
# fidelity against the exact buffer-and-dissolve
# ----------------------------------------------------------------------------

def sample_blocks(blocks, n):
    blocks = sorted(blocks)
    if n <= 0 or n >= len(blocks):
        return blocks
    return [blocks[int(i * len(blocks) / n)] for i in range(n)]


def oracle_for_blocks(scene, width_field, width, blocks, block_size):
    """{block: exact water clipped to the block} for the sample blocks,
    each from the features that reach the block only."""
    inputs = oracle.load_inputs(rivers=scene, rivers_layer='rivers', lakes=scene,
                                lakes_layer='lakes', width=width, width_field=width_field)
    rb = np.array([l.bounds for l, _ in inputs.rivers]).reshape(-1, 4)
    rw = np.array([w / 2.0 for _, w in inputs.rivers])
    lb = np.array([p.bounds for p in inputs.lakes]).reshape(-1, 4)
    out = {}
    for b in blocks:
        x0, y0 = b[0] * block_size, b[1] * block_size
        x1, y1 = x0 + block_size, y0 + block_size
        ri = np.nonzero((rb[:, 0] - rw <= x1) & (rb[:, 2] + rw >= x0) &
                        (rb[:, 1] - rw <= y1) & (rb[:, 3] + rw >= y0))[0]
        li = np.nonzero((lb[:, 0] <= x1) & (lb[:, 2] >= x0) &
                        (lb[:, 1] <= y1) & (lb[:, 3] >= y0))[0]
        sub = oracle.Inputs([inputs.rivers[i] for i in ri], [inputs.lakes[i] for i in li],
                            inputs.srs, 0)
        w = oracle.water(sub)
        c = oracle.clip_to_blocks(w, block_size, {b})
        if b in c:
            out[b] = c[b]
    return out


def fidelity(water, orc, block_size, step):
    feats = [oracle.Feat(b, g, None, {}) for b, g in water if b in orc]
    c = oracle.compare(feats, orc, block_size, 0.5, step=step)
    return {'hausdorff': c['hausdorff'], 'where': c['worst_at'], 'p99': c['p99'],
            'rel_area_diff': c['rel_area_diff'], 'blocks': len(orc), 'step': step}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('output', help='GeoPackage with a layer water')
    ap.add_argument('--block-size', type=float, default=4096.0)
    ap.add_argument('--tol', type=float, default=1e-3, help='seam tolerance, m')
    ap.add_argument('--scene', help='input GeoPackage (layers rivers, lakes) for the fidelity')
    ap.add_argument('--width-field')
    ap.add_argument('--width', type=float, default=10.0)
    ap.add_argument('--blocks', type=int, default=6, help='sampled blocks (0: all)')
    ap.add_argument('--step', type=float, default=0.1)
    a = ap.parse_args(argv)
    water = read_water(a.output)
    res = {'polygons': len(water),
           'invalid': sum(1 for _, g in water if not g.is_valid)}
    res['t_junctions'], res['gaps'], res['gap_length'] = seam_defects(water, a.block_size, 0.0)
    res['t_junctions_tol'], res['gaps_tol'], res['gap_length_tol'] = \
        seam_defects(water, a.block_size, a.tol)
    res['tol'] = a.tol
    if a.scene:
        blocks = sample_blocks({b for b, _ in water}, a.blocks)
        orc = oracle_for_blocks(a.scene, a.width_field, a.width, blocks, a.block_size)
        res.update(fidelity(water, orc, a.block_size, a.step))
    print(json.dumps(res))
    return 0


if __name__ == '__main__':
    sys.exit(main())
