#!/usr/bin/python3
"""Replays a generated recording without its odom -> base_link TF (the head's transforms stay):
the scene estimator takes the odometry from a nav_msgs/Odometry topic instead, the recording's
own /odom (odometry:=topic) or the package's visual odometry (odometry:=visual), and must still
map the objects. Private parameters: suite, scene, keyframes, rate (of the replay), odom_topic
(waited for),
odom_at_base (the odometry starts at the base of the first frame it processed, as the visual
odometry's does, rather than at the recording's map origin; which frame that was is read from the
stamp of the first odometry message, since a busy machine may drop the first frames)."""
import os
import shutil
import subprocess
import tempfile
import threading
import time
import unittest

import rospy
import rostest
from geofusion.msg import ObjectMap
from nav_msgs.msg import Odometry

import geofusion_test_utils as util

NS = '/scene_estimator'


class OdomTopicTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.maps = []
        self.first_odom_stamp = None
        rospy.Subscriber(NS + '/object_map', ObjectMap, self.on_map, queue_size=100)
        self.dir = tempfile.mkdtemp(prefix='geofusion_odom_topic_')

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def on_odom(self, msg):
        with self.lock:
            if self.first_odom_stamp is None:
                self.first_odom_stamp = msg.header.stamp.to_sec()

    def origin_frame(self, gt):
        """The ground-truth frame whose base is the odometry's origin: the one with the stamp of
        the first odometry message."""
        self.assertIsNotNone(self.first_odom_stamp, 'no odometry message was received')
        frame = min(gt['frames'], key=lambda f: abs(float(f['stamp']) - self.first_odom_stamp))
        self.assertLess(abs(float(frame['stamp']) - self.first_odom_stamp), 0.005,
                        'the first odometry message has no frame of the recording')
        return frame['map_base']

    def on_map(self, msg):
        with self.lock:
            self.maps.append(msg)

    def test_odometry_from_topic(self):
        suite = rospy.get_param('~suite', 'demo')
        scene = rospy.get_param('~scene', 'demo_01')
        keyframes = int(rospy.get_param('~keyframes', 20))
        odom_topic = rospy.get_param('~odom_topic', util.ODOM_TOPIC)
        odom_at_base = rospy.get_param('~odom_at_base', False)
        rate = float(rospy.get_param('~rate', 1.0))
        rospy.Subscriber(odom_topic, Odometry, self.on_odom, queue_size=100)
        subprocess.check_call([util.find_tool('generate_dataset'), '--suite', suite, '--out-dir',
                               self.dir, '--keyframes', str(keyframes), '--previews', '0'],
                              stdout=subprocess.DEVNULL)
        bag = os.path.join(self.dir, scene + '.bag')
        gt = util.load_yaml(os.path.join(self.dir, scene + '_gt.yaml'))
        without = os.path.join(self.dir, 'without_odom_tf.bag')
        dropped = util.strip_tf(bag, without, 'odom')
        self.assertGreater(dropped, 0, 'the recording had no odom -> base_link on /tf')
        self.assertTrue(util.wait_for_graph(util.INPUT_TOPICS + [odom_topic],
                                            [NS + '/object_map']),
                        'the estimator did not come up')
        time.sleep(1.0)
        util.play(without, rate=util.throughput_rate(rate))
        time.sleep(2.0)
        with self.lock:
            maps = list(self.maps)
        # A frame without odometry is skipped with a warning; at 30 Hz a busy machine may also
        # drop a few sets in the synchroniser, hence the margin.
        self.assertGreaterEqual(len(maps), int(0.85 * keyframes),
                                'frames were skipped (no odometry?)')
        frame = self.origin_frame(gt) if odom_at_base else None
        matched, false = util.match_objects(maps[-1].objects, gt, 0.02, frame)
        summary = '%d of %d objects matched, %d false' % (len(matched), len(gt['objects']), false)
        self.assertEqual(false, 0, summary)
        self.assertGreaterEqual(len(matched), len(gt['objects']) - 2, summary)


if __name__ == '__main__':
    rospy.init_node('odom_topic_checker')
    rostest.rosrun('geofusion', 'odom_topic', OdomTopicTest)
