#!/usr/bin/python3
"""The scene estimator nodelet started by launch/geofusion.launch with a user's configuration
file: the running estimator uses its values (dynamic_reconfigure's current values, the printed
effective configuration), a typo key is warned about with the nearest key, and a node given an
out-of-range value, an unknown model set or a bogus odometry source refuses to start, naming the
key."""
import os
import subprocess
import time
import unittest

import rospy
import rostest
import yaml
from dynamic_reconfigure.client import Client

import geofusion_test_utils as util

NS = '/scene_estimator'
HERE = os.path.dirname(os.path.abspath(__file__))


class ConfigTest(unittest.TestCase):
    def wait_for(self, condition, timeout_s=30.0):
        deadline = time.time() + timeout_s
        while time.time() < deadline:
            if condition():
                return True
            time.sleep(0.2)
        return False

    def test_1_the_running_estimator_uses_the_file(self):
        self.assertTrue(self.wait_for(lambda: rospy.has_param(NS + '/effective_config')),
                        'the estimator did not come up')
        effective = yaml.safe_load(rospy.get_param(NS + '/effective_config'))
        self.assertEqual(effective['association']['eps_fp'], 0.5)
        self.assertEqual(effective['association']['sigma_position_m'], 0.05)
        self.assertEqual(effective['stage_one']['window_keyframes'], 42)  # compile-only before
        self.assertEqual(effective['stage_one']['every_n_keyframes'], 10)  # untouched default
        # dynamic_reconfigure started from the file, not from its compiled defaults.
        current = Client(NS, timeout=10).get_configuration(timeout=10)
        self.assertAlmostEqual(current['eps_fp'], 0.5)
        self.assertAlmostEqual(current['sigma_position_m'], 0.05)
        # A reconfigure goes through the loader's range check and into the effective config.
        Client(NS, timeout=10).update_configuration({'eps_new': 0.1})
        self.assertTrue(self.wait_for(lambda: yaml.safe_load(
            rospy.get_param(NS + '/effective_config'))['association']['eps_new'] == 0.1, 10))

    def test_2_a_typo_is_warned_with_the_nearest_key(self):
        self.assertTrue(self.wait_for(lambda: rospy.has_param(NS + '/config_warnings')))
        warnings = rospy.get_param(NS + '/config_warnings')
        self.assertTrue(any('association.eps_fb: unknown, did you mean association.eps_fp?' in w
                            for w in warnings), warnings)
        # ... and printed (WARN) when the node started: a plain node prints it on its console.
        code, log = self.run_node('_params_file:=' + os.path.join(HERE, 'config',
                                                                  'estimator_settings.yaml'),
                                  '_model_set:=no_such_models')
        self.assertNotEqual(code, 0)
        self.assertIn('association.eps_fb: unknown, did you mean association.eps_fp?', log)

    def run_node(self, *params):
        """Starts a plain scene_estimator_node with private parameters; its exit code and log."""
        name = 'refusing_%d' % int(time.time() * 1000)
        args = [util.find_tool('scene_estimator_node'), '__name:=' + name] + list(params)
        p = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                           timeout=60)
        return p.returncode, p.stdout

    def test_3_bad_values_refuse_to_start_naming_the_key(self):
        code, log = self.run_node('_params_file:=' + os.path.join(HERE, 'config', 'out_of_range.yaml'))
        self.assertNotEqual(code, 0, log)
        self.assertIn('association.eps_fp', log)
        self.assertIn('[0.05, 1]', log)
        code, log = self.run_node('_model_set:=no_such_models')
        self.assertNotEqual(code, 0, log)
        self.assertIn("unknown model set 'no_such_models'", log)
        code, log = self.run_node('_odometry:=bogus')
        self.assertNotEqual(code, 0, log)
        self.assertIn('expected tf, topic or visual', log)


if __name__ == '__main__':
    rospy.init_node('config_checker')
    rostest.rosrun('geofusion', 'config_checker', ConfigTest)
