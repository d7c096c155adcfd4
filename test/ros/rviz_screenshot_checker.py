#!/usr/bin/python3
"""rviz inspecting the map (issue 23): the demo recording replayed into the estimator while rviz
shows rviz/geofusion.rviz; the map panel plugin must be up (it subscribes to
geofusion_panel/select), follow the map, highlight the object selected through it (a box around
the object and one line per contact of it, on geofusion_panel/selection) and the screenshots of
the whole scene and of the selection must show it (the highlight's yellow appears)."""
import os
import threading
import time
import unittest

import matplotlib.image
import numpy
import rospy
import rostest
from geofusion.msg import ObjectMap
from std_msgs.msg import UInt32
from visualization_msgs.msg import Marker, MarkerArray

import geofusion_test_utils as util

KEYFRAMES = 30
OUT = os.environ.get('GEOFUSION_SCREENSHOT_DIR', '/tmp')


RVIZ_WINDOW_TIMEOUT_S = 60


def screenshot(name, out=OUT):
    """The whole virtual display as an RGB array (PNG24: ImageMagick writes a screen of few
    colours, e.g. Xvfb's bare black-and-white root, as a grey-level PNG otherwise)."""
    path = os.path.join(out, name)
    util.subprocess.check_call(['import', '-window', 'root', 'PNG24:' + path])
    image = matplotlib.image.imread(path)
    if image.ndim == 2:
        image = numpy.stack([image] * 3, axis=2)
    return path, image[:, :, :3]


def colours(image):
    """Distinct colours on screen: the bare Xvfb root has two, rviz's panels and 3D view
    hundreds."""
    return len(numpy.unique((image * 255).astype(numpy.uint8).reshape(-1, 3), axis=0))


def chromatic(image):
    """Pixels in colour: rviz's grey window has a few thousand (icons), a drawn map far more."""
    return int(numpy.count_nonzero(image.max(axis=2) - image.min(axis=2) > 0.1))


def screenshot_when(name, condition, timeout_s, out=OUT):
    """Screenshots until `condition(image)` holds (rviz draws at its own pace under a software
    renderer on a busy machine) or time runs out; the last one."""
    deadline = time.time() + timeout_s
    while True:
        path, image = screenshot(name, out)
        if condition(image) or time.time() > deadline:
            return path, image
        time.sleep(1.0)


def highlighted(before, after):
    """Pixels that turned yellowish (the see-through yellow box) between two screenshots."""
    r, g, b = after[:, :, 0], after[:, :, 1], after[:, :, 2]
    changed = numpy.abs(after - before).max(axis=2) > 0.08
    return int(numpy.count_nonzero(changed & (r > 0.5) & (g > 0.45) & (r - b > 0.25)))


class RvizScreenshotTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.maps, self.selections = [], []
        rospy.Subscriber('/scene_estimator/object_map', ObjectMap, self.on_map, queue_size=10)
        rospy.Subscriber('/geofusion_panel/selection', MarkerArray, self.on_selection,
                         queue_size=10)
        self.select = rospy.Publisher('/geofusion_panel/select', UInt32, queue_size=1, latch=True)
        self.dir = util.tempfile.mkdtemp(prefix='geofusion_rviz_')

    def on_map(self, msg):
        with self.lock:
            self.maps.append(msg)

    def on_selection(self, msg):
        with self.lock:
            self.selections.append(msg)

    def test_scene_and_selection(self):
        bag = util.generate_demo(self.dir, KEYFRAMES)
        self.assertTrue(util.wait_for_graph(util.INPUT_TOPICS + ['/geofusion_panel/select'],
                                            ['/scene_estimator/object_map',
                                             '/geofusion_panel/selection'], timeout_s=60),
                        'the estimator or the rviz map panel did not come up')
        _, startup = screenshot_when('rviz_startup.png', lambda im: colours(im) > 50,
                                     RVIZ_WINDOW_TIMEOUT_S, out=self.dir)
        drawn = colours(startup)
        if drawn <= 50:
            alive = util.subprocess.call(['rosnode', 'ping', '-c', '1', '/rviz'],
                                         stdout=util.subprocess.DEVNULL) == 0
            self.fail('rviz drew no window on the virtual display in %d s (%d colours on screen; '
                      'rviz alive: %s)' % (RVIZ_WINDOW_TIMEOUT_S, drawn, alive))
        time.sleep(2.0)
        util.play(bag, rate=1.0)
        time.sleep(4.0)  # rviz draws the last map
        with self.lock:
            final = self.maps[-1]
        self.assertGreater(len(final.objects), 5)
        scene_path, scene = screenshot_when('rviz_scene.png', lambda im: chromatic(im) > 50000,
                                            timeout_s=30)
        self.assertGreater(chromatic(scene), 50000, 'rviz did not draw the map in colour')

        # The object with the most contacts with other objects (the highest of them: the top of
        # a stack shows from rviz's raised view), selected through the panel.
        def contacts_of(o):
            return [c for c in final.contacts if o.id in (c.object_a, c.object_b)]

        def with_objects(o):
            return len([c for c in contacts_of(o) if c.object_a != 0])
        chosen = max(final.objects, key=lambda o: (with_objects(o), o.pose.pose.position.z))
        self.assertGreater(len(contacts_of(chosen)), 0)
        with self.lock:
            self.selections = []
        self.select.publish(UInt32(chosen.id))
        deadline = time.time() + 10
        highlight = None
        while time.time() < deadline and highlight is None:
            with self.lock:
                for s in self.selections:
                    if any(m.type == Marker.CUBE for m in s.markers):
                        highlight = s
            time.sleep(0.1)
        self.assertIsNotNone(highlight, 'the panel published no highlight for the selection')
        box = [m for m in highlight.markers if m.type == Marker.CUBE][0]
        self.assertAlmostEqual(box.pose.position.x, chosen.pose.pose.position.x, places=6)
        lines = [m for m in highlight.markers if m.type == Marker.LINE_LIST]
        self.assertEqual(len(lines), len(contacts_of(chosen)))
        texts = [m.text for m in highlight.markers if m.type == Marker.TEXT_VIEW_FACING]
        self.assertTrue(all('(' in t for t in texts), texts)
        time.sleep(3.0)
        selected_path, selected = screenshot_when(
            'rviz_selected.png', lambda im: highlighted(scene, im) > 1000, timeout_s=30)

        self.assertEqual(scene.shape, selected.shape)
        self.assertGreater(float(numpy.std(scene)), 0.05, 'the scene screenshot is blank')
        # The highlight (see-through yellow) shows.
        self.assertGreater(highlighted(scene, selected), 1000, highlighted(scene, selected))
        rospy.loginfo('screenshots: %s, %s (object %d %s, %d contacts)', scene_path,
                      selected_path, chosen.id, chosen.class_name, len(contacts_of(chosen)))


if __name__ == '__main__':
    rospy.init_node('rviz_screenshot_checker')
    rostest.rosrun('geofusion', 'rviz_screenshots', RvizScreenshotTest)
