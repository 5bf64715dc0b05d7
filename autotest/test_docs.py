"""The documentation against the code: every open option of the driver's
XML (its type, default, range and choices) in README's options table and
docs/driver.rst with the same default and choices, the CLI's usage text in
README as the CLI prints it, with a flag for every option, and the layer
fields the docs name on the layers the driver makes."""

import os
import re
import xml.etree.ElementTree as ET

import pytest
from osgeo import gdal

REPO_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# options whose default is not one value but derived (the docs say how)
DERIVED_DEFAULT = {'RIVERS_LAYER', 'LAKES_LAYER', 'SIMPLIFY'}


def read(*parts):
    with open(os.path.join(REPO_DIR, *parts)) as f:
        return f.read()


def xml_options():
    drv = gdal.GetDriverByName('WATERMESH')
    root = ET.fromstring(drv.GetMetadataItem(gdal.DMD_OPENOPTIONLIST))
    out = {}
    for o in root.findall('Option'):
        out[o.get('name')] = dict(o.attrib, values=[v.text for v in o.findall('Value')])
    return out


def readme_options():
    """README's options table: name -> (default cell, meaning cell)."""
    text = read('README.md')
    i = text.index('| option | default | meaning |')
    rows = {}
    for line in text[i:].splitlines()[2:]:
        if not line.startswith('|'):
            break
        cells = [c.strip() for c in line.strip('|').split(' | ')]
        rows[cells[0].strip('`')] = (cells[1], ' | '.join(cells[2:]))
    return rows


def rst_options():
    """docs/driver.rst's open options: name -> {'choices': ..., 'default': ...}."""
    text = read('docs', 'driver.rst')
    out = {}
    for m in re.finditer(r'^-  \.\. oo:: (\w+)\n((?:      :\w+:.*\n)*)', text, re.M):
        fields = dict(re.findall(r':(\w+): (.*)', m.group(2)))
        out[m.group(1)] = fields
    return out


def literal(cell):
    """`10` (off) -> '10'; none -> None; other text -> itself."""
    m = re.match(r'^`([^`]*)`', cell)
    if m:
        return m.group(1)
    return None if cell == 'none' else cell


def test_every_option_documented_once_everywhere(wm):
    xml, readme, rst = xml_options(), readme_options(), rst_options()
    assert list(xml) == list(readme), (list(xml), list(readme))
    assert list(xml) == list(rst), (list(xml), list(rst))


def option_problems(name, o, readme_default, meaning, rst):
    """What disagrees about option `name` (its XML attributes o) between
    the XML, README's row and driver.rst's entry."""
    bad = []
    if o.get('type') not in ('string', 'string-select', 'float', 'int'):
        bad.append('type %r' % o.get('type'))
    if name in DERIVED_DEFAULT:
        if 'default' in o or 'default' not in o['description']:
            bad.append('a derived default, said in the description only: %r' % o)
        if literal(readme_default) != rst.get('default'):
            bad.append('README %r, driver.rst %r' % (readme_default, rst.get('default')))
    elif 'default' in o:
        if literal(readme_default) != o['default'] or rst.get('default') != o['default']:
            bad.append('default: XML %r, README %r, driver.rst %r'
                       % (o['default'], readme_default, rst.get('default')))
    elif readme_default != 'none' or 'default' in rst:
        bad.append('no default in the XML, README %r, driver.rst %r'
                   % (readme_default, rst.get('default')))
    if o['type'] == 'string-select':
        if rst.get('choices', '').split(', ') != o['values']:
            bad.append('choices: XML %r, driver.rst %r' % (o['values'], rst.get('choices')))
        bad += ['README does not name `%s`' % v for v in o['values'] if '`%s`' % v not in meaning]
    if o['type'] == 'float' and 'min' not in o:
        bad.append('a float without min')
    return ['%s: %s' % (name, b) for b in bad]


def test_option_defaults_and_choices_agree(wm):
    readme, rst = readme_options(), rst_options()
    problems = []
    for name, o in xml_options().items():
        problems += option_problems(name, o, *readme[name], rst[name])
    assert not problems, '\n'.join(problems)


def test_option_problems_are_found():
    """The checker itself: each kind of disagreement is reported."""
    o = {'type': 'string-select', 'default': 'A', 'values': ['A', 'B'], 'description': ''}
    assert option_problems('X', o, '`A`', '`A` or `B`', {'default': 'A', 'choices': 'A, B'}) == []
    assert option_problems('X', o, '`B`', '`A` or `B`', {'default': 'A', 'choices': 'A, B'})
    assert option_problems('X', o, '`A`', '`A` only', {'default': 'A', 'choices': 'A, B'})
    assert option_problems('X', o, '`A`', '`A` or `B`', {'default': 'A', 'choices': 'A'})
    f = {'type': 'float', 'default': '1', 'values': [], 'description': ''}
    assert option_problems('X', f, '`1`', '', {'default': '1'}) == ['X: a float without min']


def test_cli_usage_matches_readme_and_options(wm):
    p = wm.cli(['--help'])
    assert p.returncode == 0, p.stderr
    usage = p.stdout[:p.stdout.index('\n\n')]
    assert usage.startswith('Usage: ')
    text = read('README.md')
    block = re.search(r'```\n(gdal_watermesh \[--help\].*?)\n```', text, re.S).group(1)
    norm = lambda s: [l.strip() for l in s.splitlines()]
    assert norm(block) == norm(usage[len('Usage: '):]), (block, usage)
    for name in xml_options():
        assert re.search(r'\[-%s[ \]]' % name.lower(), usage), name
    for name, o in xml_options().items():
        if o['type'] == 'string-select':
            assert '-%s %s]' % (name.lower(), '|'.join(o['values'])) in usage, name


@pytest.mark.parametrize('form', ['MULTIPOLYGON', 'TRIANGLES'])
def test_documented_fields_are_the_layers_fields(wm, simple_options, form):
    """docs/driver.rst's field table names exactly the fields of the two
    layers (TRIANGLES has no `triangles`)."""
    text = read('docs', 'driver.rst')
    i = text.index('Field         Type        Meaning')
    table = text[i:text.index('\n\n', i)]
    documented = [(n, ty) for n, ty, rest in
                  re.findall(r'^(\w+)\s+(Integer|Real)\s+(.*)$', table, re.M)
                  if 'ELEVATION' not in rest]  # test_elevation checks those
    ds, cap = wm.open(dict(simple_options, MESH_GEOMETRY=form))
    assert ds is not None, cap.text
    have = set()
    for name in ('water', 'mesh'):
        d = ds.GetLayerByName(name).GetLayerDefn()
        for k in range(d.GetFieldCount()):
            fd = d.GetFieldDefn(k)
            have.add((fd.GetName(), {0: 'Integer', 2: 'Real'}[fd.GetType()]))
    want = set(documented)
    if form == 'TRIANGLES':
        want = {w for w in want if w[0] != 'triangles'} | {w for w in have if w[0] == 'triangles'}
    assert have == want, (sorted(have), sorted(want))


def cli_stats(wm, path, *extra):
    """-stats output of a run of the CLI on an OSM extract."""
    out = os.path.join(os.environ.get('TMPDIR', '/tmp'), 'wm_docs_%d.gpkg' % os.getpid())
    p = wm.cli(['-q', '-overwrite', '-stats', '-rivers', path, '-rivers_layer', 'rivers',
                '-lakes', path, '-lakes_layer', 'lakes'] + list(extra) + [out])
    assert p.returncode == 0, p.stderr
    os.unlink(out)
    return p.stdout


def counts(stats):
    m = re.search(r'polygons (\d+), output vertices (\d+), triangles (\d+)', stats)
    v = re.search(r'^V = ([0-9.]+)', stats, re.M).group(1)
    return [int(x) for x in m.groups()] + [v]


def marked(text, name):
    begin, end = '<!-- doc_figures:%s -->\n' % name, '<!-- /doc_figures:%s -->' % name
    return text[text.index(begin) + len(begin):text.index(end)]


def test_readme_figures_are_this_builds(wm):
    """README's results table and -stats example (tools/doc_figures.py)
    quote the counts this build gives: output vertices, triangles, V."""
    readme = read('README.md')
    table = marked(readme, 'results')
    example = counts(marked(readme, 'stats'))
    for name, f in (('Andorra', 'osm_andorra_2023.gpkg'),
                    ('Liechtenstein', 'osm_liechtenstein_2013.gpkg')):
        got = counts(cli_stats(wm, os.path.join(REPO_DIR, 'data', 'osm', f)))
        row = re.search(r'^\| %s .*$' % name, table, re.M).group(0).split(' | ')
        assert [int(row[-3].replace(',', '')), int(row[-2].replace(',', '')),
                row[-1].rstrip(' |')] == got[1:], (row, got)
        if name == 'Andorra':
            assert example == got, (example, got)


def test_methods_figures_are_this_builds(wm):
    """docs/methods.md's Andorra CONTOUR rows quote this build's vertices and
    V at each PIXEL_SIZE."""
    text = marked(read('docs', 'methods.md'), 'methods')
    andorra = text[text.index('### Andorra'):]
    path = os.path.join(REPO_DIR, 'data', 'osm', 'osm_andorra_2023.gpkg')
    for px in ('0.5', '1', '2'):
        row = re.search(r'^\| %s \| CONTOUR \| (\d+) \| ([0-9.]+) \|' % re.escape(px),
                        andorra, re.M)
        assert row, px
        got = counts(cli_stats(wm, path, '-pixel_size', px, '-simplify', px))
        assert [int(row.group(1)), row.group(2)] == [got[1], got[3]], (px, row.group(0), got)
