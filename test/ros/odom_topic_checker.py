#!/usr/bin/python3
"""Replays a generated demo recording without its odom -> base_link TF (the head's transforms
stay): the scene estimator takes the odometry from the bag's nav_msgs/Odometry topic
(~odom_topic) and must still map the objects."""
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

import geofusion_test_utils as util

NS = '/scene_estimator'
KEYFRAMES = 20


class OdomTopicTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.maps = []
        rospy.Subscriber(NS + '/object_map', ObjectMap, self.on_map, queue_size=100)
        self.dir = tempfile.mkdtemp(prefix='geofusion_odom_topic_')

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def on_map(self, msg):
        with self.lock:
            self.maps.append(msg)

    def test_odometry_from_topic(self):
        subprocess.check_call([util.find_tool('generate_dataset'), '--suite', 'demo', '--out-dir',
                               self.dir, '--keyframes', str(KEYFRAMES), '--previews', '0'],
                              stdout=subprocess.DEVNULL)
        bag = os.path.join(self.dir, 'demo_01.bag')
        gt = util.load_yaml(os.path.join(self.dir, 'demo_01_gt.yaml'))
        without = os.path.join(self.dir, 'without_odom_tf.bag')
        dropped = util.strip_tf(bag, without, 'odom')
        self.assertGreater(dropped, 0, 'the recording had no odom -> base_link on /tf')
        self.assertTrue(util.wait_for_graph(util.INPUT_TOPICS + ['/odom'],
                                            [NS + '/object_map']),
                        'the estimator did not come up')
        time.sleep(1.0)
        util.play(without, rate=1.0)
        time.sleep(2.0)
        with self.lock:
            maps = list(self.maps)
        self.assertGreaterEqual(len(maps), KEYFRAMES - 2, 'frames were skipped (no odometry?)')
        matched, false = util.match_objects(maps[-1].objects, gt, 0.02)
        self.assertEqual(false, 0)
        self.assertGreaterEqual(len(matched), len(gt['objects']) - 2)


if __name__ == '__main__':
    rospy.init_node('odom_topic_checker')
    rostest.rosrun('geofusion', 'odom_topic', OdomTopicTest)
