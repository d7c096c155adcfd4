#!/usr/bin/python3
"""Checks run_offline on a generated demo recording: the four methods run, the results file has
every keyframe and the documented fields, GeoFusion's final map matches the ground truth
(objects found at the right place, no false ones, contacts), and bad requests are refused.
A plain unittest, no ROS master (the workspace's setup.bash must be sourced):

    python3 test/ros/offline_runner_checker.py
"""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import yaml


sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import geofusion_test_utils as util  # noqa: E402

KEYFRAMES = 30
load = util.load_yaml


class OfflineRunnerTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix='geofusion_runner_')
        util.generate_demo(cls.dir, KEYFRAMES)
        cls.bag = os.path.join(cls.dir, 'demo_01.bag')
        cls.gt = load(os.path.join(cls.dir, 'demo_01_gt.yaml'))
        cls.results = {}
        for method in ('fbf', 'bslam', 'rfront', 'geofusion'):
            out = os.path.join(cls.dir, method + '.yaml')
            extra = ['--background', os.path.join(cls.dir, 'background.bt')] \
                if method == 'geofusion' else []
            p = subprocess.run([util.find_tool('run_offline'), '--bag', cls.bag, '--out', out,
                                '--method', method, '--quiet'] + extra, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, universal_newlines=True, timeout=600)
            cls.results[method] = (p.returncode, p.stdout + p.stderr,
                                   load(out) if p.returncode == 0 else None)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def test_every_method_runs_every_keyframe(self):
        names = {'fbf': 'FbF', 'bslam': 'B-SLAM', 'rfront': 'R-Front', 'geofusion': 'GeoFusion'}
        stamps = [round(float(f['stamp']), 6) for f in self.gt['frames'] if f['keyframe']]
        for method, (rc, out, res) in self.results.items():
            self.assertEqual(rc, 0, out)
            self.assertEqual(res['format'], 'geofusion_results_v1')
            self.assertEqual(res['method'], names[method])
            self.assertEqual(len(res['keyframes']), KEYFRAMES)
            self.assertEqual([round(float(k['stamp']), 6) for k in res['keyframes']], stamps)
            self.assertEqual(res['frames_skipped'], 0)
            self.assertGreater(res['recording_duration_s'], 0)
            for k in res['keyframes']:
                self.assertEqual(len(k['map_camera']), 7)
                for key in ('consistency', 'association', 'stage_one', 'relations', 'stage_two',
                            'total'):
                    self.assertGreaterEqual(k['timings_ms'][key], 0.0)
                for o in k['objects']:
                    self.assertTrue(0.0 <= o['score'] <= 1.0)
                    self.assertEqual(len(o['camera_object']), 7)

    def test_geofusion_final_map_matches_the_truth(self):
        rc, out, res = self.results['geofusion']
        self.assertEqual(rc, 0, out)
        truth = [(o['class_name'], o['pose'][:3]) for o in self.gt['objects']]
        final = res['final_map']['objects']
        matched, false = set(), 0
        for o in final:
            best, best_i = 1e9, -1
            for i, (name, p) in enumerate(truth):
                if name != o['class_name'] or i in matched:
                    continue
                d = math.dist(p, o['map_object'][:3])
                if d < best:
                    best, best_i = d, i
            if best < 0.02:
                matched.add(best_i)
            else:
                false += 1
        seen = {t for f in self.gt['frames'] if f['keyframe'] for t in f['detection_truth']
                if t >= 0}
        self.assertEqual(false, 0, final)
        self.assertGreaterEqual(len(matched), len(seen) - 1)
        # Contacts refer to objects of the final map (or -1, the support plane).
        ids = {o['id'] for o in final}
        self.assertTrue(res['final_map']['contacts'])
        for c in res['final_map']['contacts']:
            self.assertTrue(c['a'] == -1 or c['a'] in ids)
            self.assertIn(c['b'], ids)
        # The background OctoMap file was written whole.
        with open(os.path.join(self.dir, 'background.bt'), 'rb') as f:
            self.assertTrue(f.readline().startswith(b'# Octomap OcTree binary file'))
        # Fewer objects than B-SLAM, which keeps every stray detection.
        self.assertLess(len(final), len(self.results['bslam'][2]['final_map']['objects']))

    def evaluate(self, method):
        """evaluate_run on a method's results: (return code, output, evaluation JSON or None)."""
        out = os.path.join(self.dir, method + '.json')
        p = subprocess.run([util.find_tool('evaluate_run'), '--ground-truth',
                            os.path.join(self.dir, 'demo_01_gt.yaml'), '--results',
                            os.path.join(self.dir, method + '.yaml'), '--json', out],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
        data = None
        if p.returncode == 0:
            with open(out) as f:
                data = json.load(f)
        return p.returncode, p.stdout + p.stderr, data

    def test_evaluate_run_against_the_truth(self):
        rc, out, geo = self.evaluate('geofusion')
        self.assertEqual(rc, 0, out)
        self.assertIn('0 false', out)
        self.assertEqual(geo['format'], 'geofusion_evaluation_v1')
        self.assertEqual(len(geo['images']), KEYFRAMES)
        fm = geo['final_map']
        seen = {t for f in self.gt['frames'] if f['keyframe'] for t in f['detection_truth']
                if t >= 0}
        self.assertGreaterEqual(fm['matched'], len(seen) - 1)
        self.assertEqual(fm['matched'], fm['objects'])
        self.assertLess(max(fm['adds_m']), 0.01)
        self.assertLess(fm['alignment_rmse_m'], 0.02)
        c = fm['contacts']
        self.assertGreater(c['correct'], 0)
        self.assertGreaterEqual(c['correct'], 0.7 * c['estimated'])
        self.assertLess(max(fm['penetration_mm'] + [0]), 2.0)
        # Every keyframe's estimates as boxes, and most have a near-zero ADD-S to their object.
        self.assertGreater(len(geo['detections']), KEYFRAMES)
        adds = [min(d['adds_m'].values()) for d in geo['detections'] if d['adds_m']]
        self.assertGreater(sum(a < 0.01 for a in adds), 0.8 * len(adds))
        rc, out, bslam = self.evaluate('bslam')
        self.assertEqual(rc, 0, out)
        self.assertGreater(bslam['final_map']['objects'] - bslam['final_map']['matched'], 0)
        self.assertIsNone(bslam['final_map']['contacts'])
        p = subprocess.run([util.find_tool('evaluate_run'), '--results', '/nonexistent.yaml',
                            '--ground-truth', os.path.join(self.dir, 'demo_01_gt.yaml')],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
        self.assertEqual(p.returncode, 1)
        self.assertIn('nonexistent', p.stderr)
        p = subprocess.run([util.find_tool('evaluate_run'), '--results'],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
        self.assertEqual(p.returncode, 2)

    def test_bad_requests_are_refused(self):
        tool = util.find_tool('run_offline')
        p = subprocess.run([tool, '--bag', self.bag, '--out', os.path.join(self.dir, 'x.yaml'),
                            '--method', 'orbslam'], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, universal_newlines=True)
        self.assertEqual(p.returncode, 2)
        self.assertIn("method: expected one of geofusion, rfront, bslam, fbf, fbfr, got 'orbslam'",
                      p.stderr)
        p = subprocess.run([tool, '--bag', '/nonexistent.bag', '--out',
                            os.path.join(self.dir, 'y.yaml')], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, universal_newlines=True)
        self.assertEqual(p.returncode, 1)
        self.assertIn('cannot read', p.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.dir, 'y.yaml')))

    def test_the_configuration_is_read_checked_and_recorded(self):
        tool = util.find_tool('run_offline')
        config_dir = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'config')
        p = subprocess.run([tool, '--params', os.path.join(config_dir, 'estimator_settings.yaml'),
                            '--set', 'stage_one.every_n_keyframes=5', '--print-params'],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
        self.assertEqual(p.returncode, 0, p.stderr)
        printed = yaml.safe_load(p.stdout)
        self.assertEqual(printed['association']['eps_fp'], 0.5)
        self.assertEqual(printed['stage_one']['window_keyframes'], 42)
        self.assertEqual(printed['stage_one']['every_n_keyframes'], 5)
        self.assertIn('association.eps_fb: unknown, did you mean association.eps_fp?', p.stderr)
        p = subprocess.run([tool, '--params', os.path.join(config_dir, 'out_of_range.yaml'),
                            '--bag', self.bag, '--out', os.path.join(self.dir, 'z.yaml')],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
        self.assertEqual(p.returncode, 2)
        self.assertIn('association.eps_fp: expected a number in [0.001, 1], got 7.5', p.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.dir, 'z.yaml')))
        # Every results file says how it was made.
        for method, (rc, out, res) in self.results.items():
            self.assertEqual(rc, 0, out)
            self.assertEqual(res['config']['method'], method)
            self.assertEqual(res['config']['association']['eps_fp'], 0.55)


if __name__ == '__main__':
    unittest.main(verbosity=2)
