#!/usr/bin/python3
"""run_offline on recordings whose detections are vision_msgs/Detection3DArray (issue 24): a
generated vision_msgs recording gives the same map as the native recording it was made from
(with the model set's own ids and with ids mapped by vision_msgs.class_map), ids the map leaves
out are dropped and counted, and another layout or a bad class map is refused with the reason.
A plain unittest, no ROS master (the workspace's setup.bash must be sourced)."""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import geofusion_test_utils as util  # noqa: E402
import vision_bags  # noqa: E402

KEYFRAMES = 24
load = util.load_yaml


def run_offline(bag, out, *extra):
    p = subprocess.run([util.find_tool('run_offline'), '--bag', bag, '--out', out, '--quiet'] +
                       list(extra), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       universal_newlines=True, timeout=600)
    return p.returncode, p.stdout


def classes_in(bag):
    import rosbag
    seen = {}
    with rosbag.Bag(bag) as b:
        for _, msg, _ in b.read_messages(topics=[vision_bags.NATIVE_TOPIC]):
            for d in msg.detections:
                seen[d.class_name] = d.class_id
    return seen


class VisionMsgsOfflineTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix='geofusion_vision_')
        cls.native = util.generate_demo(cls.dir, KEYFRAMES)
        cls.classes = classes_in(cls.native)
        rc, out = run_offline(cls.native, cls.path('native.yaml'))
        assert rc == 0, out
        cls.native_map = load(cls.path('native.yaml'))['final_map']

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    @classmethod
    def path(cls, name):
        return os.path.join(cls.dir, name)

    def assertSameMap(self, final_map):
        native = sorted((o['id'], o['class_name'], o['map_object']) for o in self.native_map['objects'])
        other = sorted((o['id'], o['class_name'], o['map_object']) for o in final_map['objects'])
        self.assertGreater(len(native), 3)
        self.assertEqual([o[:2] for o in other], [o[:2] for o in native])
        for a, b in zip(native, other):
            for x, y in zip(a[2], b[2]):
                self.assertAlmostEqual(x, y, places=9)
        self.assertEqual(len(final_map['contacts']), len(self.native_map['contacts']))

    def test_model_set_ids_give_the_native_map(self):
        bag = self.path('vision.bag')
        written = vision_bags.to_vision_bag(self.native, bag)
        self.assertGreater(written, 50)
        rc, out = run_offline(bag, self.path('vision.yaml'), '--detections-topic',
                              vision_bags.VISION_TOPIC)
        self.assertEqual(rc, 0, out)
        self.assertIn('vision_msgs detections: %d messages, %d detections converted'
                      % (KEYFRAMES, written), out)
        self.assertSameMap(load(self.path('vision.yaml'))['final_map'])

    def test_class_map_maps_the_detectors_ids(self):
        bag = self.path('vision_ids.bag')
        vision_bags.to_vision_bag(self.native, bag, class_id=lambda d: 1000 + 3 * d.class_id)
        pairs = ', '.join('%d: %s' % (1000 + 3 * i, name) for name, i in self.classes.items())
        rc, out = run_offline(bag, self.path('vision_ids.yaml'), '--detections-topic',
                              vision_bags.VISION_TOPIC, '--set', 'vision_msgs.class_map="%s"' % pairs)
        self.assertEqual(rc, 0, out)
        self.assertSameMap(load(self.path('vision_ids.yaml'))['final_map'])

        # Without the map the model set's own ids do not match: every detection is dropped,
        # counted with its ids, and the run says why it made no keyframe with objects.
        rc, out = run_offline(bag, self.path('vision_unmapped.yaml'), '--detections-topic',
                              vision_bags.VISION_TOPIC)
        self.assertIn('detections without a mapped class (ids', out)
        self.assertIn('map them with vision_msgs.class_map', out)

    def test_ids_left_out_of_the_map_are_dropped(self):
        bag = self.path('vision_part.bag')
        vision_bags.to_vision_bag(self.native, bag)
        kept = sorted(self.classes.items())[:2]
        pairs = ', '.join('%d: %s' % (i, name) for name, i in kept)
        rc, out = run_offline(bag, self.path('vision_part.yaml'), '--detections-topic',
                              vision_bags.VISION_TOPIC, '--set', 'vision_msgs.class_map="%s"' % pairs)
        self.assertEqual(rc, 0, out)
        self.assertIn('detections without a mapped class', out)
        names = {o['class_name'] for o in load(self.path('vision_part.yaml'))['final_map']['objects']}
        self.assertTrue(names)
        self.assertLessEqual(names, {name for name, _ in kept})

    def test_another_layout_and_a_bad_map_are_refused(self):
        bag = self.path('vision_string_ids.bag')
        vision_bags.to_vision_bag(self.native, bag, id_type='string')
        rc, out = run_offline(bag, self.path('string_ids.yaml'), '--detections-topic',
                              vision_bags.VISION_TOPIC)
        self.assertEqual(rc, 1, out)
        self.assertIn('Noetic layout (MD5 05c51d9aea1fb4cfdc8effb94f197b6f)', out)
        self.assertFalse(os.path.exists(self.path('string_ids.yaml')))

        rc, out = run_offline(self.path('vision.bag') if os.path.exists(self.path('vision.bag'))
                              else self.native, self.path('bad_map.yaml'), '--set',
                              'vision_msgs.class_map="3: not_a_class"')
        self.assertEqual(rc, 1, out)
        self.assertIn("class 'not_a_class' (id 3) is not in the model set", out)


if __name__ == '__main__':
    unittest.main()
