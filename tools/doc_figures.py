#!/usr/bin/python3
"""Regenerates the figures the docs quote, from this build: README's results
table and its -stats example (both OpenStreetMap extracts, default options,
2 threads, best of N by process wall time), and docs/methods.md's CONTOUR /
PAPER tables (tools/compare_methods.py). Each lies between the markers
<!-- doc_figures:NAME --> and <!-- /doc_figures:NAME -->, which this
rewrites in place; autotest/test_docs.py checks the columns that do not
depend on the machine (vertices, triangles, V) against the code.

Usage, from a built tree, on an idle machine:
    /usr/bin/python3 tools/doc_figures.py [--repeat N] [--no-methods]
"""

import argparse
import contextlib
import io
import os
import platform
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, 'tools'))
CLI = os.path.join(ROOT, 'gdal_watermesh')
OSM = os.path.join(ROOT, 'data', 'osm')
SCENES = [('Andorra', os.path.join(OSM, 'osm_andorra_2023.gpkg')),
          ('Liechtenstein', os.path.join(OSM, 'osm_liechtenstein_2013.gpkg'))]
STAGES = ('field', 'extraction', 'simplification', 'holes', 'triangulation')


def cli_args(path, out):
    return ['-q', '-overwrite', '-stats', '-num_threads', '2', '-rivers', path,
            '-rivers_layer', 'rivers', '-lakes', path, '-lakes_layer', 'lakes', out]


def best_run(path, out, repeat):
    """(stdout, process wall s, peak RSS MB) of the fastest of `repeat` runs."""
    best = None
    for _ in range(repeat):
        p = subprocess.run(['/usr/bin/time', '-f', 'TIME %e %M', CLI] + cli_args(path, out),
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True, check=True)
        wall, rss = re.search(r'^TIME ([0-9.]+) (\d+)$', p.stderr, re.M).groups()
        run = (p.stdout, float(wall), int(rss) / 1024.0)
        if best is None or run[1] < best[1]:
            best = run
    return best


def parse(stats):
    """The -stats figures README's table quotes."""
    num = lambda pat: re.search(pat, stats, re.M).group(1)
    d = {s: float(num(r'^%s\s+([0-9.]+)' % s)) for s in STAGES}
    d['wall'] = float(num(r'^total \(wall\)\s+([0-9.]+)'))
    d['vertices'] = int(num(r'output vertices (\d+)'))
    d['triangles'] = int(num(r'triangles (\d+)$'))
    d['V'] = float(num(r'^V = ([0-9.]+)'))
    d['river'] = int(num(r'(\d+) river'))
    d['lake'] = int(num(r'(\d+) lake vertices'))
    return d


def results(repeat):
    """README's results table and its -stats example."""
    rows, example = [], None
    with tempfile.TemporaryDirectory() as tmp:
        for name, path in SCENES:
            stats, wall, rss = best_run(path, os.path.join(tmp, 'out.gpkg'), repeat)
            d = parse(stats)
            example = example or stats
            rows.append('| %s (%s river + %s lake vertices) | %s | %.2f s | %.2f s | %.0f MB '
                        '| %s | %s | %.3f |' % (
                            name, format(d['river'], ','), format(d['lake'], ','),
                            ' | '.join('%.3f s' % d[s] for s in STAGES), d['wall'], wall,
                            rss, format(d['vertices'], ','), format(d['triangles'], ','),
                            d['V']))
    table = ('| scene | field | extraction | simplification | holes | triangulation | wall '
             '| process | peak RSS | output vertices | triangles | V |\n'
             + '|---' * 12 + '|\n' + '\n'.join(rows) + '\n')
    return table, '```\n' + example + '```\n'


def machine():
    cpu = ''
    with open('/proc/cpuinfo') as f:
        for line in f:
            if line.startswith('model name'):
                cpu = line.split(':', 1)[1].strip()
                break
    return '%s, %d logical CPUs, Linux %s, %s' % (cpu, os.cpu_count(), platform.release(),
                                                 time.strftime('%Y-%m-%d'))


def methods_tables():
    import compare_methods
    buf = io.StringIO()
    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(buf):
        compare_methods.table(tmp)
    return 'Measured on %s.\n\n%s' % (machine(), buf.getvalue())


def replace(path, name, text):
    with open(path) as f:
        doc = f.read()
    begin, end = '<!-- doc_figures:%s -->\n' % name, '<!-- /doc_figures:%s -->' % name
    i, j = doc.index(begin) + len(begin), doc.index(end)
    with open(path, 'w') as f:
        f.write(doc[:i] + text + doc[j:])
    print('%s: %s rewritten' % (os.path.relpath(path, ROOT), name), file=sys.stderr)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--repeat', type=int, default=3, help='runs per scene (fastest kept)')
    ap.add_argument('--no-methods', action='store_true', help="leave docs/methods.md's tables")
    a = ap.parse_args()
    if not os.access(CLI, os.X_OK):
        sys.exit('%s is not built: run make first' % CLI)
    readme = os.path.join(ROOT, 'README.md')
    table, example = results(a.repeat)
    replace(readme, 'results', 'Measured on %s.\n\n%s' % (machine(), table))
    replace(readme, 'stats', example)
    if not a.no_methods:
        replace(os.path.join(ROOT, 'docs', 'methods.md'), 'methods', methods_tables())


if __name__ == '__main__':
    main()
