#!/usr/bin/python3
"""run_offline under deliberate faults (issue 21): each recording made by the test from a good one
(test/ros/fault_bags.py). Every fault is counted by reason in the results, or refused with a
reason a user can act on and nothing written. A plain unittest, no ROS master:

    python3 test/ros/offline_faults_checker.py
"""
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fault_bags  # noqa: E402
import geofusion_test_utils as util  # noqa: E402

KEYFRAMES = 20


class OfflineFaultsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix='geofusion_faults_')
        util.generate_demo(cls.dir, KEYFRAMES)
        cls.good = os.path.join(cls.dir, 'demo_01.bag')
        cls.baseline = cls.run_offline(cls.good, 'good')

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    @classmethod
    def run_offline(cls, bag, name, *extra):
        out = os.path.join(cls.dir, name + '.yaml')
        start = time.time()
        p = subprocess.run([util.find_tool('run_offline'), '--bag', bag, '--out', out,
                            '--model-set', 'primitives', '--quiet'] + list(extra),
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True, timeout=600)
        results = util.load_yaml(out) if os.path.exists(out) else None
        return p.returncode, p.stdout + p.stderr, results, out, time.time() - start

    def faulty(self, name):
        return os.path.join(self.dir, name + '.bag')

    def test_the_good_recording_drops_nothing(self):
        rc, text, res, _, _ = self.baseline
        self.assertEqual(rc, 0, text)
        self.assertEqual(res['frames_skipped'], 0, text)
        self.assertEqual(res['frames_dropped'], {})
        self.assertEqual(res['detections_dropped'], {})
        self.assertGreaterEqual(len(res['keyframes']), KEYFRAMES - 1)

    def test_a_gap_in_odometry_drops_its_frames_instead_of_guessing(self):
        bag = self.faulty('tf_gap')
        g0, g1 = fault_bags.tf_gap(self.good, bag, length_s=1.5)
        rc, text, res, _, _ = self.run_offline(bag, 'tf_gap')
        self.assertEqual(rc, 0, text)
        self.assertGreater(res['frames_dropped'].get('odometry gap', 0), 0, text)
        self.assertIn('odometry gap', text)
        inside = [k for k in res['keyframes'] if g0 < float(k['stamp']) < g1]
        self.assertEqual(inside, [], 'keyframes made inside the odometry gap')

    def test_frames_before_the_odometry_have_no_camera_pose(self):
        bag = self.faulty('late_odometry')
        first = fault_bags.odometry_starts_late(self.good, bag, delay_s=1.0)
        rc, text, res, _, _ = self.run_offline(bag, 'late_odometry')
        self.assertEqual(rc, 0, text)
        self.assertGreater(res['frames_dropped'].get('no camera pose', 0), 0, text)
        self.assertNotIn('odometry gap', res['frames_dropped'])
        early = [k for k in res['keyframes'] if float(k['stamp']) < first - 0.05]
        self.assertEqual(early, [], 'keyframes made before the odometry started')

    def test_a_broken_depth_image_is_unusable_depth(self):
        bag = self.faulty('broken_depth')
        broken = fault_bags.broken_depth(self.good, bag)
        self.assertGreater(broken, 0)
        rc, text, res, _, _ = self.run_offline(bag, 'broken_depth')
        self.assertEqual(rc, 0, text)
        self.assertEqual(res['frames_dropped'].get('unusable depth', 0), broken, text)
        self.assertEqual(res['frames_skipped'], sum(res['frames_dropped'].values()))

    def test_tools_without_the_workspace_say_to_source_it(self):
        """Started without the workspace's environment, a tool that reads the package's files
        stops saying what to do; it never goes on with other data than the user named."""
        env = {'PATH': '/usr/bin:/bin', 'HOME': os.environ.get('HOME', '/tmp')}
        for tool, args in (('consistency_benchmark', ['--models', self.dir, '--rounds', '1']),
                           ('generate_dataset', ['--suite', 'demo', '--out-dir',
                                                 os.path.join(self.dir, 'unsourced')])):
            p = subprocess.run([util.find_tool(tool)] + args, env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, universal_newlines=True, timeout=120)
            self.assertEqual(p.returncode, 1, p.stdout)
            self.assertIn("source the workspace's setup.bash first", p.stdout)
            self.assertNotIn('built-in primitives', p.stdout)

    def test_late_detections_are_counted_out_of_order(self):
        bag = self.faulty('late')
        delayed = fault_bags.late_detections(self.good, bag)
        self.assertGreater(delayed, 0)
        rc, text, res, _, _ = self.run_offline(bag, 'late')
        self.assertEqual(rc, 0, text)
        dropped = res['frames_dropped']
        # Each late frame is used, or dropped as out of order or unsynchronised: never lost in
        # silence.
        used = res['frames_seen'] - res['frames_skipped']
        self.assertEqual(used + dropped.get('unsynchronised', 0) + dropped.get('out of order', 0),
                         self.baseline[2]['frames_seen'], text)
        self.assertGreater(dropped.get('out of order', 0) + dropped.get('unsynchronised', 0), 0)

    def test_five_thousand_detections_in_a_frame_are_capped(self):
        bag = self.faulty('flood')
        fault_bags.flooded_detections(self.good, bag, count=5000)
        rc, text, res, _, seconds = self.run_offline(bag, 'flood')
        self.assertEqual(rc, 0, text)
        capped = res['detections_dropped'].get('over max_detections', 0)
        self.assertGreaterEqual(capped, 4900, text)
        self.assertIn('max_detections_per_frame', text)
        self.assertLess(seconds, 4 * self.baseline[4] + 30, 'the flood stalled the run')

    def test_unknown_classes_are_counted_not_used(self):
        bag = self.faulty('unknown')
        renamed = fault_bags.unknown_classes(self.good, bag)
        rc, text, res, _, _ = self.run_offline(bag, 'unknown')
        self.assertEqual(rc, 0, text)
        self.assertEqual(res['detections_dropped'].get('unknown class', 0), renamed, text)

    def test_stamps_that_never_match_say_why_and_write_nothing(self):
        bag = self.faulty('shifted')
        fault_bags.shifted_detection_stamps(self.good, bag, shift_s=0.07)  # frames 0.2 s apart
        rc, text, res, out, _ = self.run_offline(bag, 'shifted')
        self.assertEqual(rc, 1, text)
        self.assertIsNone(res, 'results written by a failed run')
        self.assertIn('no keyframe', text)
        self.assertIn(util.DETECTIONS_TOPIC + ' (geofusion/DetectionArray)', text)
        self.assertIn('0.070 s apart (more than input.sync_max_interval_s)', text)
        self.assertFalse([f for f in os.listdir(self.dir) if f.startswith('shifted.yaml')])

    def test_a_missing_topic_is_named(self):
        rc, text, res, _, _ = self.run_offline(self.good, 'missing', '--detections-topic',
                                               '/my_detector/detections')
        self.assertEqual(rc, 1, text)
        self.assertIsNone(res)
        self.assertIn('Missing: /my_detector/detections', text)

    def test_a_truncated_bag_says_reindex_and_writes_nothing(self):
        bag = self.faulty('truncated')
        fault_bags.truncated(self.good, bag)
        rc, text, res, _, _ = self.run_offline(bag, 'truncated')
        self.assertEqual(rc, 1, text)
        self.assertIsNone(res)
        self.assertIn('rosbag reindex', text)

    def test_an_unwritable_output_is_refused_before_the_run(self):
        out = os.path.join(self.dir, 'no_such_folder', 'results.yaml')
        start = time.time()
        p = subprocess.run([util.find_tool('run_offline'), '--bag', self.good, '--out', out,
                            '--model-set', 'primitives', '--quiet'], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, universal_newlines=True, timeout=120)
        self.assertEqual(p.returncode, 1, p.stdout)
        self.assertIn('cannot write', p.stdout)
        self.assertIn('nothing was run', p.stdout)
        self.assertLess(time.time() - start, self.baseline[4], 'the run was made before the check')

    def test_a_saved_map_is_continued_after_a_restart(self):
        prefix = os.path.join(self.dir, 'saved_map')
        rc, text, first, _, _ = self.run_offline(
            self.good, 'first', '--save-map', prefix,
            '--background', os.path.join(self.dir, 'first.bt'))
        self.assertEqual(rc, 0, text)
        saved = util.load_yaml(prefix + '.yaml')
        self.assertIn('map', saved)
        bt = os.path.join(self.dir, saved['map']['background']['file'])
        self.assertTrue(os.path.exists(bt))
        # The same recording again, continuing the saved map: the same objects, none doubled.
        rc, text, second, _, _ = self.run_offline(self.good, 'second', '--initial-map', prefix)
        self.assertEqual(rc, 0, text)
        self.assertIn('continuing the map', text)
        ids_first = {o['id'] for o in first['final_map']['objects']}
        ids_second = {o['id'] for o in second['final_map']['objects']}
        self.assertGreaterEqual(len(ids_first & ids_second), len(ids_first) - 1,
                                (ids_first, ids_second))
        self.assertLessEqual(len(ids_second), len(ids_first) + 1)
        # A background that is not the one saved with the map is refused; nothing runs.
        with open(bt, 'ab') as f:
            f.write(b'x')
        rc, text, res, _, _ = self.run_offline(self.good, 'third', '--initial-map', prefix)
        self.assertEqual(rc, 1, text)
        self.assertIn('do not belong together', text)
        self.assertIsNone(res)


if __name__ == '__main__':
    unittest.main()
