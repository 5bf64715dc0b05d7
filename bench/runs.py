"""What bench/run, bench/shards and bench/diff share: a command timed by
/usr/bin/time -v, and the features of a watermesh output."""

import re
import subprocess
import sys

from osgeo import gdal


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def parse_time_v(text):
    """(wall s, peak RSS KB, user + sys s) from /usr/bin/time -v's report."""
    rss = int(re.search(r'Maximum resident set size \(kbytes\): (\d+)', text).group(1))
    el = re.search(r'Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)', text).group(1)
    wall = 0.0
    for part in el.split(':'):
        wall = wall * 60 + float(part)
    cpu = sum(float(re.search(r'%s time \(seconds\): ([0-9.]+)' % k, text).group(1))
              for k in ('User', 'System'))
    return wall, rss, cpu


def timed(cmd, env=None, who='bench'):
    """Runs cmd under /usr/bin/time -v: (stdout, wall s, peak RSS KB, CPU s);
    exits with the command's output when it fails."""
    log('  $ ' + ' '.join(cmd))
    p = subprocess.run(['/usr/bin/time', '-v'] + cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit('%s: command failed (%d):\n%s%s' % (who, p.returncode, p.stdout, p.stderr))
    return (p.stdout,) + parse_time_v(p.stderr)


def features(path):
    """Per output layer (water, mesh): [(FID, fields, ISO WKB)] in FID order."""
    ds = gdal.OpenEx(path, gdal.OF_VECTOR)
    out = {}
    for name in ('water', 'mesh'):
        lyr = ds.GetLayerByName(name)
        out[name] = [(f.GetFID(), [f.GetField(i) for i in range(f.GetFieldCount())],
                      bytes(f.GetGeometryRef().ExportToIsoWkb())) for f in lyr]
    ds = None
    return out
