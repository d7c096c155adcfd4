#!/usr/bin/python3
"""Checks src/tools/validate_bag.py on bags written by make_synthetic_bag and on broken copies of
them. A plain unittest, no ROS master needed (the workspace's setup.bash must be sourced so that
make_synthetic_bag and rosbag are found):

    python3 test/ros/validate_bag_checker.py
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

import rosbag
import rospy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import geofusion_test_utils as util  # noqa: E402

VALIDATOR = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'src', 'tools',
                         'validate_bag.py')
RGB = util.RGB_TOPIC
DEPTH = util.DEPTH_TOPIC
DETECTIONS = util.DETECTIONS_TOPIC


def run(*args):
    """Runs the validator; returns (exit code, stdout lines, stderr)."""
    p = subprocess.run([VALIDATOR] + [str(a) for a in args], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, universal_newlines=True, timeout=600)
    return p.returncode, p.stdout.splitlines(), p.stderr


def lines_with(lines, prefixes, *words):
    """Report lines starting with one of prefixes and containing every word."""
    return [ln for ln in lines if ln.startswith(prefixes) and all(w in ln for w in words)]


def copy_bag(src, dst, rewrite=None, loop=False):
    """Copies src to dst; rewrite(topic, msg) may change a message or return None to drop it.
    loop=True appends every message once more, same messages (header stamps included), recorded
    1 s after the end of the first pass: a bag that loops."""
    with rosbag.Bag(src) as inp, rosbag.Bag(dst, 'w') as out:
        duration = inp.get_end_time() - inp.get_start_time()
        passes = [rospy.Duration(0)]
        if loop:
            passes.append(rospy.Duration(duration + 1.0))
        for shift in passes:
            for topic, msg, t in inp.read_messages():
                if rewrite is not None:
                    msg = rewrite(topic, msg)
                    if msg is None:
                        continue
                out.write(topic, msg, t + shift)


class ValidateBagTest(unittest.TestCase):
    dirs = []

    @classmethod
    def setUpClass(cls):
        cls.clean, cls.clean_gt = cls.make('clean', '--frames', 20)

    @classmethod
    def tearDownClass(cls):
        for d in cls.dirs:
            shutil.rmtree(d, ignore_errors=True)

    @classmethod
    def make(cls, name, *args):
        bag, gt = util.make_bag(name, *args)
        cls.dirs.append(os.path.dirname(bag))
        return bag, gt

    def scratch(self, name):
        d = tempfile.mkdtemp(prefix='geofusion_validate_')
        self.dirs.append(d)
        return os.path.join(d, name)

    def check_report_format(self, lines):
        self.assertTrue(lines, 'no output')
        self.assertTrue(lines[-1].startswith('SUMMARY: '), lines[-1])
        for ln in lines[:-1]:
            self.assertRegex(ln, r'^(ERROR|WARNING|OK): ')

    def test_executable(self):
        self.assertTrue(os.access(VALIDATOR, os.X_OK), VALIDATOR + ' is not executable')
        with open(VALIDATOR) as f:
            self.assertEqual(f.readline().rstrip('\n'), '#!/usr/bin/python3')

    def test_clean_bag(self):
        code, lines, err = run(self.clean)
        self.check_report_format(lines)
        self.assertEqual(code, 0, '\n'.join(lines) + err)
        self.assertEqual(lines_with(lines, ('ERROR',)), [])
        self.assertEqual(lines_with(lines, ('WARNING',)), [])
        self.assertTrue(lines_with(lines, ('OK',), DETECTIONS, 'all 20 detection messages'),
                        '\n'.join(lines))
        self.assertTrue(lines[-1].startswith('SUMMARY: 0 errors, 0 warnings'), lines[-1])
        # --quiet: only the summary is left for a clean bag.
        code, lines, _ = run(self.clean, '--quiet')
        self.assertEqual(code, 0)
        self.assertEqual(len(lines), 1, lines)

    def test_16bit_depth(self):
        bag, _ = self.make('depth16', '--frames', 20, '--depth-encoding', '16UC1')
        code, lines, err = run(bag)
        self.check_report_format(lines)
        self.assertEqual(code, 0, '\n'.join(lines) + err)
        self.assertEqual(lines_with(lines, ('ERROR',)), [])
        self.assertTrue(lines_with(lines, ('OK',), DEPTH, '16UC1'), '\n'.join(lines))

    def test_tf_stops(self):
        bag, gt = self.make('tf_until', '--frames', 20, '--tf-until', 5)
        code, lines, _ = run(bag)
        self.check_report_format(lines)
        self.assertEqual(code, 0, '\n'.join(lines))  # a warning: frames are lost, not all
        found = lines_with(lines, ('WARNING', 'ERROR'), '/tf', 'odom -> base_link', 'missing')
        self.assertEqual(len(found), 1, '\n'.join(lines))
        # The stretch: from the last transform (frame 5) to the last image, 14 images in it.
        last_tf, last_image = gt['frames'][5]['stamp'], gt['frames'][-1]['stamp']
        self.assertIn('%.3f' % last_tf, found[0])
        self.assertIn('%.3f' % last_image, found[0])
        self.assertIn('%.2f s' % (last_image - last_tf), found[0])
        self.assertIn('14 images', found[0])

    def with_camera_info(self, name, model, D):
        """A copy of the clean bag whose camera_info says this lens."""
        out = self.scratch(name + '.bag')
        with rosbag.Bag(self.clean) as inp, rosbag.Bag(out, 'w') as bag:
            for topic, msg, t in inp.read_messages():
                if msg._type == 'sensor_msgs/CameraInfo':
                    msg.distortion_model, msg.D = model, D
                bag.write(topic, msg, t)
        return out

    def test_lens_distortion(self):
        # A plumb_bob lens is rectified: said, no problem.
        code, lines, err = run(self.with_camera_info('plumb_bob', 'plumb_bob',
                                                     [0.2312, -0.7849, -0.0033, -0.0001, 0.9172]))
        self.assertEqual(code, 0, '\n'.join(lines) + err)
        self.assertTrue(lines_with(lines, ('OK',), 'lens distortion plumb_bob'), '\n'.join(lines))
        # A fisheye lens would drop every frame: an error naming the model.
        code, lines, _ = run(self.with_camera_info('fisheye', 'equidistant', [0.1, 0.01, 0, 0]))
        self.assertNotEqual(code, 0, '\n'.join(lines))
        found = lines_with(lines, ('ERROR',), "'equidistant' is not supported")
        self.assertEqual(len(found), 1, '\n'.join(lines))
        self.assertIn('unusable camera_info', found[0])

    def test_malformed_detections(self):
        bag, gt = self.make('malformed', '--frames', 20, '--malformed-every', 3)
        code, lines, _ = run(bag)
        self.check_report_format(lines)
        self.assertEqual(code, 0, '\n'.join(lines))
        found = lines_with(lines, ('WARNING',), DETECTIONS, 'malformed')
        self.assertEqual(len(found), 1, '\n'.join(lines))
        m = re.search(r'(\d+) of (\d+) detections are malformed', found[0])
        self.assertTrue(m, found[0])
        self.assertGreater(int(m.group(1)), 0)
        self.assertEqual(int(m.group(1)), sum(f['malformed'] for f in gt['frames']))
        for kind in ('non-finite pose', 'zero quaternion', 'non-unit quaternion'):
            self.assertIn(kind, found[0])

    def test_detections_stamped_late(self):
        bag, _ = self.make('stamp_offset', '--frames', 20, '--detection-stamp-offset', 0.5)
        code, lines, _ = run(bag)
        self.check_report_format(lines)
        self.assertEqual(code, 1, '\n'.join(lines))
        found = lines_with(lines, ('ERROR',), DETECTIONS, 'no detection message synchronises')
        self.assertEqual(len(found), 1, '\n'.join(lines))
        self.assertIn('+0.500 s', found[0])

    def test_missing_topic(self):
        bag = self.scratch('no_detections.bag')
        copy_bag(self.clean, bag, lambda topic, msg: None if topic == DETECTIONS else msg)
        code, lines, _ = run(bag)
        self.check_report_format(lines)
        self.assertEqual(code, 1, '\n'.join(lines))
        self.assertTrue(lines_with(lines, ('ERROR: %s:' % DETECTIONS,), 'not in the bag'),
                        '\n'.join(lines))

    def test_unknown_frame(self):
        def reframe(topic, msg):
            if topic == DETECTIONS:
                msg.header.frame_id = 'nowhere_frame'
            return msg

        bag = self.scratch('nowhere.bag')
        copy_bag(self.clean, bag, reframe)
        code, lines, _ = run(bag)
        self.check_report_format(lines)
        self.assertEqual(code, 1, '\n'.join(lines))
        self.assertTrue(lines_with(lines, ('ERROR: %s:' % DETECTIONS,),
                                   "unknown frame 'nowhere_frame'"), '\n'.join(lines))
        # The images are still in a known frame, and the frames now differ.
        self.assertFalse(lines_with(lines, ('ERROR',), RGB), '\n'.join(lines))
        self.assertTrue(lines_with(lines, ('WARNING: %s:' % DETECTIONS,), 'nowhere_frame',
                                   util.CAMERA_FRAME), '\n'.join(lines))

    def test_looping_bag(self):
        bag = self.scratch('looping.bag')
        copy_bag(self.clean, bag, loop=True)
        _, lines, _ = run(bag)
        self.check_report_format(lines)
        for topic in (RGB, DEPTH, DETECTIONS):
            found = lines_with(lines, ('WARNING: %s:' % topic, 'ERROR: %s:' % topic), 'backwards')
            self.assertEqual(len(found), 1, '\n'.join(lines))
            self.assertIn('1 time', found[0])

    def test_missing_file(self):
        missing = self.scratch('does_not_exist.bag')
        code, lines, err = run(missing)
        self.assertEqual(code, 2)
        self.assertNotIn('Traceback', err + '\n'.join(lines))
        self.assertIn(missing, err)

    def test_not_a_bag(self):
        path = self.scratch('garbage.bag')
        with open(path, 'w') as f:
            f.write('this is not a bag\n' * 100)
        code, lines, err = run(path)
        self.assertEqual(code, 2)
        self.assertNotIn('Traceback', err + '\n'.join(lines))
        self.assertIn(path, err)

    def test_usage(self):
        code, _, err = run()
        self.assertEqual(code, 2)
        self.assertIn('usage', err)
        code, _, err = run(self.clean, '--max-sync-spread', 'abc')
        self.assertEqual(code, 2)
        self.assertNotIn('Traceback', err)


if __name__ == '__main__':
    unittest.main(verbosity=2)
