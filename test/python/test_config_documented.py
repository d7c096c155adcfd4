#!/usr/bin/python3
"""docs/parameters.md documents every key the loader reads (and no other), and
cfg/SceneEstimator.cfg lists exactly the loader's reconfigurable settings, with the same ranges
and defaults.

  test_config_documented.py GEOFUSION_CONFIG_TOOL   (run in the devel environment)"""
import os
import re
import subprocess
import sys
import unittest

SRC = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..')
TOOL = None


def loader_keys():
    rows = {}
    out = subprocess.check_output([TOOL, 'keys'], text=True)
    for line in out.splitlines():
        key, kind, allowed, default, reconfigure, doc = line.split('\t')
        rows[key] = dict(kind=kind, allowed=allowed, default=default, reconfigure=reconfigure,
                         doc=doc)
    return rows


def documented_keys():
    """The keys of docs/parameters.md's configuration tables: rows `| `key` | ...` under
    "## Configuration"."""
    with open(os.path.join(SRC, 'docs', 'parameters.md')) as f:
        text = f.read()
    start = text.index('\n## Configuration')
    end = text.find('\n## ', start + 1)
    section = text[start:end if end > 0 else len(text)]
    return set(re.findall(r'^\| `([a-z_][a-z0-9_.]*)` \|', section, re.M))


class ConfigDocumented(unittest.TestCase):
    def test_docs_document_every_key_and_no_other(self):
        loaded, documented = set(loader_keys()), documented_keys()
        self.assertGreater(len(documented), 50, 'docs/parameters.md has no configuration table')
        self.assertEqual(sorted(loaded - documented), [],
                         'keys the loader reads, missing from docs/parameters.md')
        self.assertEqual(sorted(documented - loaded), [],
                         'keys docs/parameters.md documents, unknown to the loader')

    def test_reconfigurable_settings_match_the_cfg(self):
        from geofusion.cfg import SceneEstimatorConfig as cfg
        rows = loader_keys()
        by_name = {r['reconfigure']: (k, r) for k, r in rows.items() if r['reconfigure']}
        self.assertEqual(sorted(by_name), sorted(cfg.defaults),
                         'cfg/SceneEstimator.cfg and the loader list different reconfigurable settings')
        for name, (key, row) in by_name.items():
            lo, hi = re.match(r'.*\[(\S+), (\S+)\]', row['allowed']).groups()
            self.assertAlmostEqual(float(lo), cfg.min[name], msg='%s (%s) minimum' % (name, key))
            self.assertAlmostEqual(float(hi), cfg.max[name], msg='%s (%s) maximum' % (name, key))
            self.assertAlmostEqual(float(row['default']), cfg.defaults[name],
                                   msg='%s (%s) default' % (name, key))


if __name__ == '__main__':
    TOOL = sys.argv.pop(1)
    unittest.main()
