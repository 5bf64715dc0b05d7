"""Independent block jobs (docs/distributed.md): -list-blocks, -shard i/N
(-shard-env), -resume, GNU Parallel with --joblog / --resume-failed, a job
killed mid-run, and the merge recipe (ogr2ogr -append in shard order),
whose result equals a single process's feature for feature."""

import os
import signal
import subprocess
import time

import pytest
from osgeo import gdal

from conftest import CLI_PATH, DATA_DIR

ANDORRA = os.path.join(DATA_DIR, 'osm_andorra_2023.gpkg')
ARGS = ['-rivers', ANDORRA, '-rivers_layer', 'rivers', '-lakes', ANDORRA,
        '-lakes_layer', 'lakes']


def cli(*args, env=None):
    return subprocess.run([CLI_PATH] + list(args), stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, universal_newlines=True, env=env,
                          timeout=600)


def blocks(*extra, env=None):
    p = cli('-list-blocks', *(ARGS + list(extra)), env=env)
    assert p.returncode == 0, p.stderr
    return [tuple(int(v) for v in l.split()) for l in p.stdout.splitlines()]


def features(path):
    """Every feature of both layers: FID, fields, WKB, in order."""
    ds = gdal.OpenEx(path, gdal.OF_VECTOR)
    out = {}
    for name in ('water', 'mesh'):
        lyr = ds.GetLayerByName(name)
        out[name] = [(f.GetFID(), [f.GetField(i) for i in range(f.GetFieldCount())],
                      f.GetGeometryRef().ExportToWkb()) for f in lyr]
    ds = None
    return out


def merge(shards, dst):
    """The recipe of docs/distributed.md: ogr2ogr -append, in shard order."""
    for s in shards:
        p = subprocess.run(['ogr2ogr', '-append', dst, s], stderr=subprocess.PIPE,
                           universal_newlines=True)
        assert p.returncode == 0, p.stderr


@pytest.fixture(scope='module')
def single(tmp_path_factory):
    out = str(tmp_path_factory.mktemp('single') / 'single.gpkg')
    p = cli('-q', *(ARGS + [out]))
    assert p.returncode == 0, p.stderr
    return features(out)


@pytest.mark.parametrize('n', [1, 3, 4, 64])
def test_shards_partition_the_blocks(n):
    """The jobs' blocks are disjoint and in the whole run's order. A job
    reads only the features within its cells and the halo, so a block that
    only a far river's bounding box reached (no water) is not listed."""
    every = blocks()
    parts = sum([blocks('-shard', '%d/%d' % (i, n)) for i in range(n)], [])
    assert len(set(parts)) == len(parts) and len(every) > 40
    assert parts == [b for b in every if b in set(parts)]
    assert len(parts) >= 0.9 * len(every)


def test_shard_env():
    env = dict(os.environ, SLURM_ARRAY_TASK_ID='2')
    assert blocks('-shard', '4', '-shard-env', 'SLURM_ARRAY_TASK_ID', env=env) == \
        blocks('-shard', '2/4')
    for bad, msg in ((['-shard', '4/4'], 'SHARD=4/4'), (['-shard', '4'], '-shard needs'),
                     (['-shard', '4', '-shard-env', 'NO_SUCH_VAR_X'], 'NO_SUCH_VAR_X')):
        p = cli('-list-blocks', *(ARGS + bad))
        assert p.returncode != 0 and msg in p.stderr, (bad, p.stderr)


def test_gnu_parallel_resume_failed_and_merge(tmp_path, single):
    """Four shards on GNU Parallel, one failing the first time; parallel
    --resume-failed reruns it alone; the merge equals a single run."""
    out = tmp_path / 'shards'
    out.mkdir()
    (tmp_path / 'stop_1').write_text('')
    job = ('test -e %s/stop_{} && exit 3; %s -q %s -shard {}/4 -shard-plan %s/plan.txt '
           '%s/shard_{}.gpkg' % (tmp_path, CLI_PATH, ' '.join(ARGS), tmp_path, out))
    log = str(tmp_path / 'jobs.log')
    run = lambda *extra: subprocess.run(['parallel', '-j', '2', '--joblog', log] + list(extra)
                                        + [job, ':::', '0', '1', '2', '3'],
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        universal_newlines=True, timeout=600)
    p = run()
    assert p.returncode == 1, p.stderr  # one job failed
    assert sorted(os.listdir(out)) == ['shard_0.gpkg', 'shard_2.gpkg', 'shard_3.gpkg']
    mtimes = {f: os.stat(out / f).st_mtime_ns for f in os.listdir(out)}
    os.unlink(tmp_path / 'stop_1')
    p = run('--resume-failed')
    assert p.returncode == 0, p.stderr
    assert {f: os.stat(out / f).st_mtime_ns for f in mtimes} == mtimes
    merged = str(tmp_path / 'merged.gpkg')
    merge([str(out / ('shard_%d.gpkg' % i)) for i in range(4)], merged)
    assert features(merged) == single


def test_killed_job_leaves_nothing_and_resumes(tmp_path, single):
    """A job killed mid-run leaves no output; -resume then skips the shards
    already done and computes the rest; the merge equals a single run."""
    out = tmp_path / 'shards'
    out.mkdir()
    dst = lambda i: str(out / ('shard_%d.gpkg' % i))
    for i in (0, 2):
        assert cli('-q', *(ARGS + ['-shard', '%d/3' % i, dst(i)])).returncode == 0
    proc = subprocess.Popen([CLI_PATH, '-q', '-num_threads', '1', '-pixel_size', '0.25']
                            + ARGS + ['-shard', '1/3', dst(1)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    time.sleep(0.5)
    assert proc.poll() is None, 'the job ended before it could be killed'
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=30) != 0
    assert sorted(os.listdir(out)) == ['shard_0.gpkg', 'shard_2.gpkg']
    before = os.stat(dst(0)).st_mtime_ns
    for i in range(3):
        p = cli('-resume', *(ARGS + ['-shard', '%d/3' % i, dst(i)]))
        assert p.returncode == 0, p.stderr
        assert ('skipped (-resume)' in p.stderr) == (i != 1), p.stderr
    assert os.stat(dst(0)).st_mtime_ns == before
    merged = str(tmp_path / 'merged.gpkg')
    merge([dst(i) for i in range(3)], merged)
    assert features(merged) == single


def test_many_shards_of_a_reprojected_pbf(tmp_path):
    """16 jobs on the Liechtenstein PBF with the OSM preset (WGS 84 read
    through each job's own spatial filter, widths by class, a halo from
    the widest class): merged, the single run's features."""
    pbf = os.path.join(DATA_DIR, 'liechtenstein-2013-08-03.osm.pbf')
    preset = os.path.join(DATA_DIR, 'osm.watermesh')
    args = ['-q', '-rivers', pbf, '-lakes', pbf, preset]
    one = str(tmp_path / 'single.gpkg')
    assert cli(*(args + [one])).returncode == 0
    shards = []
    for i in range(16):
        shards.append(str(tmp_path / ('shard_%d.gpkg' % i)))
        p = cli(*(args[:1] + ['-shard', '%d/16' % i] + args[1:] + [shards[-1]]))
        assert p.returncode == 0, p.stderr
    merged = str(tmp_path / 'merged.gpkg')
    merge(shards, merged)
    want = features(one)
    assert len(want['water']) > 50
    assert features(merged) == want


def test_output_does_not_depend_on_feature_order(tmp_path):
    """A job reads its features through a spatial filter, in the order the
    source's index gives; whatever depends on the order of the inputs
    breaks the shard contract. The extract with both layers in reversed
    order gives the same features (a rule keyed on the order of river
    segments once made 317 blocks of L5 differ between shards and a
    single run)."""
    rev = str(tmp_path / 'reversed.gpkg')
    for i, name in enumerate(('rivers', 'lakes')):
        gdal.VectorTranslate(rev, ANDORRA, format='GPKG', accessMode='append' if i else None,
                             SQLStatement='SELECT * FROM %s ORDER BY fid DESC' % name,
                             layerName=name, options=['-unsetFid'])
    got = []
    for src in (ANDORRA, rev):
        out = str(tmp_path / ('out_%s.gpkg' % os.path.basename(src)))
        p = cli('-q', '-rivers', src, '-rivers_layer', 'rivers', '-lakes', src,
                '-lakes_layer', 'lakes', '-width_field', 'width', '-simplify', '0', out)
        assert p.returncode == 0, p.stderr
        got.append(features(out))
    firsts = []
    for path in (ANDORRA, rev):
        ds = gdal.OpenEx(path, gdal.OF_VECTOR)
        lyr = ds.GetLayerByName('rivers')
        firsts.append([f.GetGeometryRef().ExportToWkb() for f in lyr])
        ds = None
    assert firsts[1] == firsts[0][::-1], 'the copy is not reversed'
    assert got[0]['water'] and got[0] == got[1]


def test_shard_plan_spares_the_scan(tmp_path, single):
    """-shard-plan: the first job (here -list-blocks) scans the inputs and
    writes the grid's envelope and widest river to the plan; the jobs that
    find it read only their features (no scan) and merge into the single
    run's output."""
    plan = str(tmp_path / 'plan.txt')
    assert blocks('-shard', '0/1', '-shard-plan', plan) == blocks()
    text = open(plan).read()
    assert text.startswith('WATERMESH_SHARD_PLAN 1\nkey ') and '\nenvelope ' in text, text
    shards = []
    for i in range(3):
        dst = str(tmp_path / ('shard_%d.gpkg' % i))
        p = cli('-q', '--debug', 'on', *(ARGS + ['-shard', '%d/3' % i, '-shard-plan', plan,
                                                dst]))
        assert p.returncode == 0, p.stderr
        assert 'SHARD_PLAN %s read: no scan' % plan in p.stderr, p.stderr
        shards.append(dst)
    merged = str(tmp_path / 'merged.gpkg')
    merge(shards, merged)
    assert features(merged) == single


def test_shard_plan_bad(tmp_path):
    """A plan made for other inputs or options, one that is not a plan, one
    that cannot be written, and -shard-plan without -shard: errors naming
    the plan, nothing written."""
    plan = str(tmp_path / 'plan.txt')
    assert cli('-list-blocks', *(ARGS + ['-shard', '0/1', '-shard-plan', plan])).returncode == 0
    dst = str(tmp_path / 'out.gpkg')
    p = cli('-q', *(ARGS + ['-width', '30', '-shard', '0/2', '-shard-plan', plan, dst]))
    assert p.returncode != 0 and 'was made for other inputs' in p.stderr and plan in p.stderr, \
        p.stderr
    junk = str(tmp_path / 'junk.txt')
    with open(junk, 'w') as f:
        f.write('not a plan\n')
    p = cli('-q', *(ARGS + ['-shard', '0/2', '-shard-plan', junk, dst]))
    assert p.returncode != 0 and 'is not a plan' in p.stderr and junk in p.stderr, p.stderr
    nowhere = str(tmp_path / 'no_such_dir' / 'plan.txt')
    p = cli('-q', *(ARGS + ['-shard', '0/2', '-shard-plan', nowhere, dst]))
    assert p.returncode != 0 and 'cannot be written' in p.stderr and nowhere in p.stderr, \
        p.stderr
    p = cli('-q', *(ARGS + ['-shard-plan', plan, dst]))
    assert p.returncode != 0 and '-shard-plan needs -shard or -blocks' in p.stderr, p.stderr
    assert not os.path.exists(dst)


def test_blocks_compute_the_named_blocks(tmp_path, single):
    """-blocks X:Y[,...] (indices or ranges a..b): exactly the named blocks
    that hold water, each as in the whole run; with -shard, the named
    blocks of the job's share; a bad list is an error naming it."""
    every = blocks()
    pick = every[5:9] + every[-3:]
    spec = ','.join('%d:%d' % b for b in pick)
    assert blocks('-blocks', spec) == pick
    x0, y0 = every[20]
    rng = '%d..%d:%d..%d' % (x0 - 1, x0 + 1, y0, y0 + 1)
    assert blocks('-blocks', rng) == [b for b in every
                                      if x0 - 1 <= b[0] <= x0 + 1 and y0 <= b[1] <= y0 + 1]
    assert blocks('-blocks', spec, '-shard', '1/2') == [b for b in pick
                                                       if b in blocks('-shard', '1/2')]
    dst = str(tmp_path / 'some.gpkg')
    p = cli('-q', *(ARGS + ['-blocks', spec, dst]))
    assert p.returncode == 0, p.stderr
    got = features(dst)
    for name in ('water', 'mesh'):  # FIDs are the output's own
        want = [f[1:] for f in single[name] if tuple(f[1][:2]) in set(pick)]
        assert [f[1:] for f in got[name]] == want and want, name
    for bad in ('1:', '1..0:3', 'a:b', '1:2:3', '1:2,,'):
        p = cli('-list-blocks', *(ARGS + ['-blocks', bad]))
        assert p.returncode != 0 and 'BLOCKS=%s' % bad in p.stderr, (bad, p.stderr)
