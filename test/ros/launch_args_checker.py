#!/usr/bin/python3
"""Launch arguments are checked when roslaunch reads the files (issue 21): a wrong value or a
missing required argument stops roslaunch with exit code 1 and says what is wrong, before anything
starts; good values pass. `roslaunch --nodes` only reads the files (no master). A plain unittest:

    python3 test/ros/launch_args_checker.py
"""
import subprocess
import unittest


def roslaunch(launch, *args):
    p = subprocess.run(['roslaunch', '--nodes', 'geofusion', launch] + list(args),
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       universal_newlines=True, timeout=60)
    return p.returncode, p.stdout


class LaunchArgumentsTest(unittest.TestCase):
    def refused(self, expected, launch, *args):
        rc, out = roslaunch(launch, *args)
        self.assertEqual(rc, 1, out)
        self.assertIn(expected, out)

    def test_wrong_values_are_refused_with_the_reason(self):
        self.refused('odometry:=bogus is not one of tf, topic, visual', 'geofusion.launch',
                     'odometry:=bogus')
        self.refused('odometry:=topic needs odom_topic:=', 'geofusion.launch', 'odometry:=topic')
        self.refused('method:=slam is not one of', 'geofusion.launch', 'method:=slam')
        self.refused('odometry:=bogus', 'fetch.launch', 'odometry:=bogus')
        self.refused('rate:=0 must be a number above 0', 'replay.launch', 'bag:=x.bag', 'rate:=0')
        self.refused('camera:=kinect3 is not one of fetch, realsense', 'geofusion.launch',
                     'camera:=kinect3')
        self.refused('detections:=yolo is not one of geofusion, vision_msgs', 'geofusion.launch',
                     'detections:=yolo')

    def test_a_missing_bag_is_refused(self):
        self.refused("requires the 'bag' arg to be set", 'demo.launch')
        self.refused("requires the 'bag' arg to be set", 'replay.launch')

    def test_good_values_pass(self):
        for launch, args in (('geofusion.launch', ['odometry:=topic', 'odom_topic:=/odom']),
                             ('geofusion.launch', ['odometry:=visual', 'method:=rfront']),
                             ('replay.launch', ['bag:=x.bag', 'rate:=2.5']),
                             ('demo.launch', ['bag:=x.bag'])):
            rc, out = roslaunch(launch, *args)
            self.assertEqual(rc, 0, out)

    def test_detections_in_vision_msgs_start_the_adapter(self):
        rc, out = roslaunch('geofusion.launch')
        self.assertEqual(rc, 0, out)
        self.assertNotIn('/vision_detections_adapter', out)
        rc, out = roslaunch('geofusion.launch', 'detections:=vision_msgs')
        self.assertEqual(rc, 0, out)
        self.assertIn('/vision_detections_adapter', out)
        self.assertIn('/scene_estimator', out)

    def test_each_camera_gives_its_drivers_topics(self):
        expected = {'fetch': 'head_camera/depth_registered/image_raw',
                    'realsense': 'camera/aligned_depth_to_color/image_raw',
                    'azure_kinect': 'depth_to_rgb/image_raw',
                    'openni2': 'camera/depth_registered/image_raw',
                    'zed': 'zed2/zed_node/depth/depth_registered'}
        for camera, depth in expected.items():
            p = subprocess.run(['roslaunch', '--dump-params', 'geofusion', 'geofusion.launch',
                                'camera:=' + camera], stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, universal_newlines=True, timeout=60)
            self.assertEqual(p.returncode, 0, p.stdout)
            self.assertIn("/scene_estimator/depth_topic: %s" % depth, p.stdout)


if __name__ == '__main__':
    unittest.main()
