#!/usr/bin/python3
"""The scene estimator nodelet under deliberate faults (issue 21): a recording with a gap in its
odometry, a frame of 5000 detections and detections of a class no model set has is replayed. The
node keeps mapping, counts each fault by reason in its diagnostics, and decides as run_offline
decides on the same recording (the shared ingestion path)."""
import os
import re
import shutil
import subprocess
import tempfile
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from geofusion.msg import ObjectMap

import fault_bags
import geofusion_test_utils as util

NS = '/scene_estimator'
KEYFRAMES = 24


class EstimatorFaultsTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.maps, self.diagnostics = [], []
        rospy.Subscriber(NS + '/object_map', ObjectMap, self.on_map, queue_size=100)
        rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics, queue_size=100)
        self.dir = tempfile.mkdtemp(prefix='geofusion_node_faults_')

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def on_map(self, msg):
        with self.lock:
            self.maps.append(msg)

    def on_diagnostics(self, msg):
        with self.lock:
            self.diagnostics.extend(s for s in msg.status if 'scene estimator' in s.name)

    def test_faults_are_counted_and_decided_as_offline(self):
        util.generate_demo(self.dir, KEYFRAMES)
        good = os.path.join(self.dir, 'demo_01.bag')
        gap_bag, flood_bag, bag = (os.path.join(self.dir, n + '.bag')
                                   for n in ('gap', 'flood', 'faulty'))
        g0, g1 = fault_bags.tf_gap(good, gap_bag, length_s=1.5)
        fault_bags.flooded_detections(gap_bag, flood_bag, frame=3, count=5000)
        renamed = fault_bags.unknown_classes(flood_bag, bag)
        self.assertGreater(renamed, 0)

        self.assertTrue(util.wait_for_graph(util.INPUT_TOPICS, [NS + '/object_map']),
                        'the estimator did not come up')
        time.sleep(1.0)
        # The node must decide every frame as run_offline does: a rate it keeps up with (under
        # ThreadSanitizer at 1x its queue overflowed, 9 frames).
        util.play(bag, rate=util.throughput_rate(1.0))
        time.sleep(3.0)  # two diagnostics periods
        with self.lock:
            maps, diagnostics = list(self.maps), list(self.diagnostics)
        self.assertTrue(diagnostics, 'no diagnostics from the estimator')
        values = {kv.key: kv.value for kv in diagnostics[-1].values}
        # Still mapping after the faults: maps with objects after the gap.
        after_gap = [m for m in maps if m.header.stamp.to_sec() > g1 and m.objects]
        self.assertTrue(after_gap, 'no map after the odometry gap')
        self.assertFalse([m for m in maps if g0 < m.header.stamp.to_sec() < g1],
                         'keyframes made inside the odometry gap')
        node_gap = int(values['frames dropped: odometry gap'])
        self.assertGreater(node_gap, 0, values)
        detections = values['detections']
        self.assertIn('over max_detections', detections)
        self.assertIn('unknown class', detections)

        # run_offline on the same recording decides the same.
        out = os.path.join(self.dir, 'offline.yaml')
        p = subprocess.run([util.find_tool('run_offline'), '--bag', bag, '--out', out,
                            '--model-set', 'primitives', '--quiet'], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, universal_newlines=True, timeout=300)
        self.assertEqual(p.returncode, 0, p.stdout)
        offline = util.load_yaml(out)
        self.assertEqual(node_gap, offline['frames_dropped'].get('odometry gap', 0),
                         '%s\n%s' % (values, p.stdout))
        self.assertEqual(values['frames dropped'], '%d dropped (%d odometry gap)' % (
            node_gap, node_gap), 'the node dropped frames run_offline did not')
        over = int(re.search(r'(\d+) over max_detections', detections).group(1))
        self.assertEqual(over, offline['detections_dropped'].get('over max_detections', 0))
        unknown = int(re.search(r'(\d+) unknown class', detections).group(1))
        self.assertEqual(unknown, offline['detections_dropped'].get('unknown class', 0))


if __name__ == '__main__':
    rospy.init_node('estimator_faults_checker')
    rostest.rosrun('geofusion', 'estimator_faults', EstimatorFaultsTest)
