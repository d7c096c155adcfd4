#!/usr/bin/python3
"""Checks generate_dataset end to end on the demo suite: the recording passes the bag validator,
agrees with its ground-truth file message by message, is deterministic, cached and remade on
request, and the tool refuses bad requests with a reason. A plain unittest, no ROS master
(the workspace's setup.bash must be sourced):

    python3 test/ros/dataset_checker.py
"""
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import rosbag

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import geofusion_test_utils as util  # noqa: E402

VALIDATOR = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'src', 'tools',
                         'validate_bag.py')
KEYFRAMES = 24


def generate(out_dir, *args):
    p = subprocess.run([util.find_tool('generate_dataset'), '--suite', 'demo', '--out-dir', out_dir,
                        '--keyframes', str(KEYFRAMES), '--previews', '2'] + list(args),
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
                       timeout=600)
    return p.returncode, p.stdout


def digest(path):
    with open(path, 'rb') as f:
        return hashlib.sha256(f.read()).hexdigest()


def matrix(pose):
    """4x4 from [x, y, z, qx, qy, qz, qw]."""
    x, y, z, qx, qy, qz, qw = pose
    m = np.eye(4)
    m[:3, :3] = np.array(util.rotation(qx, qy, qz, qw))
    m[:3, 3] = [x, y, z]
    return m


def tf_matrix(t):
    return matrix([t.translation.x, t.translation.y, t.translation.z, t.rotation.x, t.rotation.y,
                   t.rotation.z, t.rotation.w])


class DatasetTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix='geofusion_dataset_')
        cls.rc, cls.out = generate(cls.dir)
        cls.bag = os.path.join(cls.dir, 'demo_01.bag')
        cls.gt_path = os.path.join(cls.dir, 'demo_01_gt.yaml')
        cls.gt = util.load_yaml(cls.gt_path)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def test_generation_reports_calibration(self):
        self.assertEqual(self.rc, 0, self.out)
        self.assertIn('ADD-S AUC', self.out)
        self.assertIn('odometry drift', self.out)
        self.assertTrue(os.path.exists(os.path.join(self.dir, 'calibration_densefusion.txt')))
        previews = os.listdir(os.path.join(self.dir, 'previews'))
        self.assertEqual(len([p for p in previews if p.endswith('_rgb.png')]), 2)
        self.assertFalse([p for p in os.listdir(self.dir) if p.endswith('.tmp')])

    def test_bag_passes_the_validator(self):
        p = subprocess.run([VALIDATOR, self.bag], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True, timeout=300)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        self.assertIn('0 errors, 0 warnings', p.stdout)

    def test_ground_truth_matches_the_bag(self):
        gt = self.gt
        self.assertEqual(gt['format'], 'geofusion_ground_truth_v1')
        n_objects = len(gt['objects'])
        self.assertGreaterEqual(n_objects, 8)
        for c in gt['contacts']:
            self.assertTrue(-1 <= c['a'] < n_objects and 0 <= c['b'] < n_objects, c)
            self.assertIn(c['type'], ('P2P', 'P2C', 'C2C', 'P2E'))
        self.assertTrue(any(c['a'] == -1 for c in gt['contacts']), 'the table supports nothing')
        frames = gt['frames']
        keyframes = [f for f in frames if f['keyframe']]
        self.assertEqual(len(keyframes), KEYFRAMES)
        by_stamp = {round(float(f['stamp']), 6): f for f in frames}
        images, detections, odom, tf = [], [], [], {}
        with rosbag.Bag(self.bag) as bag:
            for topic, msg, t in bag.read_messages():
                if topic == util.RGB_TOPIC:
                    images.append(msg.header.stamp.to_sec())
                elif topic == util.DETECTIONS_TOPIC:
                    detections.append(msg)
                elif topic == util.ODOM_TOPIC:
                    odom.append(msg)
                elif topic == '/tf':
                    for tr in msg.transforms:
                        tf[(tr.child_frame_id, round(tr.header.stamp.to_sec(), 6))] = tr
                elif topic == '/tf_static':
                    link_optical = tf_matrix(msg.transforms[-1].transform)
        self.assertEqual(len(odom), len(frames))
        self.assertEqual([round(s, 6) for s in images],
                         [round(float(f['stamp']), 6) for f in keyframes])
        # Every detection message belongs to a keyframe and has one truth entry a detection.
        self.assertEqual(len(detections), KEYFRAMES)
        for msg in detections:
            f = by_stamp[round(msg.header.stamp.to_sec(), 6)]
            self.assertEqual(len(msg.detections), len(f['detection_truth']))
            self.assertEqual(len(f['visible_fraction']), n_objects)
        # TF odom->base_link is the recorded (drifting) odometry; the camera's true pose is the
        # true base pose chained with the head and optical transforms from the bag.
        drift = []
        for f in frames[::7]:
            stamp = round(float(f['stamp']), 6)
            base = tf[(util.BASE_FRAME, stamp)]
            np.testing.assert_allclose(tf_matrix(base.transform), matrix(f['odom_base']),
                                       atol=1e-6)
            head = tf_matrix(tf[(util.CAMERA_LINK_FRAME, stamp)].transform)
            camera = matrix(f['map_base']) @ head @ link_optical
            np.testing.assert_allclose(camera, matrix(f['map_camera']), atol=1e-6)
            drift.append(np.linalg.norm(matrix(f['map_base'])[:3, 3] -
                                        matrix(f['odom_base'])[:3, 3]))
        self.assertGreater(max(drift), 0.0005, 'odometry does not drift at all')
        self.assertLess(max(drift), 0.05, 'odometry drifts more than a real robot')

    def test_cached_then_remade_identically(self):
        before = digest(self.gt_path), os.path.getmtime(self.bag)
        rc, out = generate(self.dir)
        self.assertEqual(rc, 0, out)
        self.assertIn('demo_01: cached', out)
        self.assertEqual(os.path.getmtime(self.bag), before[1])
        rc, out = generate(self.dir, '--force')
        self.assertEqual(rc, 0, out)
        self.assertNotIn('demo_01: cached', out)
        self.assertEqual(digest(self.gt_path), before[0], 'same seed, different ground truth')
        # A different request is not served from the cache.
        other = tempfile.mkdtemp(prefix='geofusion_dataset_')
        try:
            shutil.copy(self.bag, other)
            shutil.copy(self.gt_path, other)
            shutil.copy(os.path.join(self.dir, 'demo_01.request'), other)
            rc, out = generate(other, '--image-every', '3')
            self.assertEqual(rc, 0, out)
            self.assertNotIn('demo_01: cached', out)
        finally:
            shutil.rmtree(other, ignore_errors=True)

    def test_bad_requests_are_refused(self):
        tool = util.find_tool('generate_dataset')
        p = subprocess.run([tool, '--suite', 'nonsense'], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, universal_newlines=True)
        self.assertEqual(p.returncode, 2)
        self.assertIn('unknown suite', p.stderr)
        p = subprocess.run([tool, '--suite', 'bench', '--models', '/nonexistent', '--out-dir',
                            os.path.join(self.dir, 'b')], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, universal_newlines=True)
        self.assertEqual(p.returncode, 1)
        self.assertIn('YCB-Video models', p.stderr)
        p = subprocess.run([tool, '--suite', 'demo', '--scenes', 'demo_99'],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True)
        self.assertEqual(p.returncode, 2)
        self.assertIn('demo_99', p.stderr)


if __name__ == '__main__':
    unittest.main(verbosity=2)
