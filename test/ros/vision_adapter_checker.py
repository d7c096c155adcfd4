#!/usr/bin/python3
"""The vision_msgs adapter nodelet live (issue 24): the demo recording, its detections rewritten as
vision_msgs/Detection3DArray (with a decoy hypothesis of an unmapped class on each), is replayed;
every DetectionArray the adapter publishes equals the native recording's message of that stamp
(class, id, score, pose), and the scene estimator builds its map from them."""
import os
import shutil
import tempfile
import threading
import time
import unittest

import rosbag
import rospy
import rostest
from geofusion.msg import DetectionArray, ObjectMap

import geofusion_test_utils as util
import vision_bags

KEYFRAMES = 16


class VisionAdapterTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.received, self.maps = {}, []
        rospy.Subscriber('/detections', DetectionArray, self.on_detections, queue_size=100)
        rospy.Subscriber('/scene_estimator/object_map', ObjectMap, self.on_map, queue_size=10)
        self.dir = tempfile.mkdtemp(prefix='geofusion_vision_adapter_')

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def on_detections(self, msg):
        with self.lock:
            self.received[msg.header.stamp.to_nsec()] = msg

    def on_map(self, msg):
        with self.lock:
            self.maps.append(msg)

    def test_adapter_output_equals_the_native_detections(self):
        native = util.generate_demo(self.dir, KEYFRAMES)
        bag = os.path.join(self.dir, 'vision.bag')
        self.assertGreater(vision_bags.to_vision_bag(native, bag), 30)
        expected = {}
        with rosbag.Bag(native) as b:
            for _, msg, _ in b.read_messages(topics=[vision_bags.NATIVE_TOPIC]):
                expected[msg.header.stamp.to_nsec()] = msg

        self.assertTrue(util.wait_for_graph(['/vision_detections', '/detections'],
                                            ['/detections', '/scene_estimator/object_map']),
                        'the adapter and the estimator did not come up')
        time.sleep(1.0)
        util.play(bag, rate=1.0)
        time.sleep(2.0)

        with self.lock:
            received, maps = dict(self.received), list(self.maps)
        self.assertEqual(sorted(received), sorted(expected))
        for stamp, want in expected.items():
            got = received[stamp]
            self.assertEqual(got.header.frame_id, want.header.frame_id)
            self.assertEqual(len(got.detections), len(want.detections))
            for g, w in zip(got.detections, want.detections):
                self.assertEqual((g.class_name, g.class_id), (w.class_name, w.class_id))
                self.assertAlmostEqual(g.score, w.score, places=6)
                for a, b in ((g.pose.position, w.pose.position),
                             (g.pose.orientation, w.pose.orientation)):
                    for field in a.__slots__:
                        self.assertEqual(getattr(a, field), getattr(b, field))
        self.assertTrue(maps, 'the estimator published no map')
        names = {o.class_name for o in maps[-1].objects}
        self.assertGreater(len(names), 3)


if __name__ == '__main__':
    rospy.init_node('vision_adapter_checker')
    rostest.rosrun('geofusion', 'vision_adapter', VisionAdapterTest)
