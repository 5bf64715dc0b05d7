"""gdal_watermesh -of GLB: one binary glTF 2.0 file per block, valid for
the Khronos validator (npm gltf-validator, installed by bootstrap.sh), with
the mesh layer's triangles, and an index of the blocks."""

import json
import os
import struct
import subprocess

import pytest
from osgeo import gdal

from conftest import DATA_DIR

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VALIDATE = os.path.join(REPO, 'tools', 'gltf_validate.js')
ANDORRA = os.path.join(DATA_DIR, 'osm_andorra_2023.gpkg')


@pytest.fixture(scope='module')
def simple_args(wm, simple_options):
    return wm.cli_args(simple_options)


def read_glb(path):
    """(JSON, positions [(x, y, z)], indices) of a GLB file."""
    with open(path, 'rb') as f:
        data = f.read()
    magic, version, length = struct.unpack_from('<III', data, 0)
    assert (magic, version, length) == (0x46546C67, 2, len(data))
    jl, jt = struct.unpack_from('<II', data, 12)
    assert jt == 0x4E4F534A and jl % 4 == 0
    doc = json.loads(data[20:20 + jl])
    bl, bt = struct.unpack_from('<II', data, 20 + jl)
    assert bt == 0x004E4942 and bl % 4 == 0 and 28 + jl + bl == len(data)
    bin_ = data[28 + jl:]
    pos_acc, idx_acc = doc['accessors']
    n = pos_acc['count']
    pos = struct.unpack_from('<%df' % (3 * n), bin_, doc['bufferViews'][0]['byteOffset'])
    idx = struct.unpack_from('<%dI' % idx_acc['count'], bin_, doc['bufferViews'][1]['byteOffset'])
    return doc, [pos[3 * i:3 * i + 3] for i in range(n)], idx


def validate(files):
    node = subprocess.run(['node', VALIDATE] + files, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, universal_newlines=True, timeout=600)
    reports = [json.loads(l) for l in node.stdout.splitlines()]
    assert len(reports) == len(files), node.stderr
    return node.returncode, reports


def glb_run(wm, args, out):
    p = wm.cli(args + ['-q', '-of', 'GLB', out])
    assert p.returncode == 0, p.stderr
    with open(os.path.join(out, 'index.json')) as f:
        return json.load(f)


def triangle_sets(index, out):
    """{(bx, by): sorted triangles in world coordinates (rounded to 1 mm)}."""
    tris = {}
    for b in index['blocks']:
        doc, pos, idx = read_glb(os.path.join(out, b['file']))
        x0, y0 = b['origin']
        world = [(round(x0 + p[0], 3), round(y0 - p[2], 3)) for p in pos]
        tris[tuple(b['block'])] = sorted(tuple(sorted(world[i] for i in idx[k:k + 3]))
                                         for k in range(0, len(idx), 3))
    return tris


@pytest.mark.parametrize('scene', ['simple', 'andorra'])
def test_glb_valid_and_complete(wm, simple_options, simple_args, tmp_dir, scene):
    """Every file passes the Khronos validator with 0 errors and 0 warnings;
    the files hold the mesh layer's triangles, block by block, at the same
    places (to a millimetre); index.json, origins, extras and bounds agree."""
    if scene == 'simple':
        args, opts = simple_args, simple_options
    else:
        args = ['-rivers', ANDORRA, '-rivers_layer', 'rivers', '-lakes', ANDORRA,
                '-lakes_layer', 'lakes']
        opts = {'RIVERS': ANDORRA, 'RIVERS_LAYER': 'rivers', 'LAKES': ANDORRA,
                'LAKES_LAYER': 'lakes'}
    out = os.path.join(tmp_dir, 'glb_' + scene)
    index = glb_run(wm, args, out)
    files = [os.path.join(out, b['file']) for b in index['blocks']]
    assert sorted(os.listdir(out)) == sorted([b['file'] for b in index['blocks']] + ['index.json'])
    rc, reports = validate(files)
    assert rc == 0 and all(r['errors'] == 0 and r['warnings'] == 0 for r in reports), reports[:3]
    block = float(opts.get('BLOCK_SIZE', 4096))
    want = {}
    ds, cap = wm.open(opts)
    for f in ds.GetLayerByName('mesh'):
        g = f.GetGeometryRef()
        key = (f['block_x'], f['block_y'])
        for i in range(g.GetGeometryCount()):
            ring = g.GetGeometryRef(i).GetGeometryRef(0)
            want.setdefault(key, []).append(tuple(sorted(
                (round(ring.GetX(k), 3), round(ring.GetY(k), 3)) for k in range(3))))
    ds = None
    got = triangle_sets(index, out)
    assert got == {k: sorted(v) for k, v in want.items()}
    assert sum(len(v) for v in got.values()) == sum(b['triangles'] for b in index['blocks']) > 0
    for b in index['blocks']:
        doc, pos, idx = read_glb(os.path.join(out, b['file']))
        extras = doc['scenes'][0]['extras']
        assert extras['block'] == b['block'] and extras['origin'][:2] == b['origin']
        assert b['origin'] == [b['block'][0] * block, b['block'][1] * block]
        assert extras['crs'] == index['crs'] == 'EPSG:%d' % (32631 if scene == 'andorra' else
                                                             wm.scenes.SCENE_EPSG)
        assert len(idx) == 3 * b['triangles'] and len(pos) == b['vertices']
        assert all(0 <= p[0] <= block and p[1] == 0 and -block <= p[2] <= 0 for p in pos)


def test_glb_overwrite_replaces_the_folder(wm, simple_args, tmp_dir):
    """-overwrite replaces the whole folder: a second run on fewer blocks
    leaves no file of the first beside its index; a trailing / works."""
    out = os.path.join(tmp_dir, 'glb_again')
    first = glb_run(wm, simple_args, out + '/')
    b = first['blocks'][0]
    x0, y0 = b['origin']
    p = wm.cli(simple_args + ['-q', '-overwrite', '-spat', str(x0 + 1), str(y0 + 1),
                              str(x0 + 2), str(y0 + 2), '-of', 'GLB', out])
    assert p.returncode == 0, p.stderr
    with open(os.path.join(out, 'index.json')) as f:
        second = json.load(f)
    assert len(second['blocks']) < len(first['blocks'])
    assert sorted(os.listdir(out)) == sorted([x['file'] for x in second['blocks']] + ['index.json'])


def test_glb_refuses_existing_folder(wm, simple_args, tmp_dir):
    out = os.path.join(tmp_dir, 'glb_exists')
    os.mkdir(out)
    with open(os.path.join(out, 'keep.txt'), 'w') as f:
        f.write('mine')
    p = wm.cli(simple_args + ['-q', '-of', 'GLB', out])
    assert p.returncode != 0 and 'already exists' in p.stderr, p.stderr
    assert os.listdir(out) == ['keep.txt']
    p = wm.cli(simple_args + ['-q', '-overwrite', '-of', 'GLB', out])
    assert p.returncode == 0, p.stderr
    assert 'index.json' in os.listdir(out) and 'keep.txt' not in os.listdir(out)
