#!/usr/bin/python3
"""The scene estimator nodelet started by launch/geofusion.launch with a user's configuration
file: the running estimator uses its values (dynamic_reconfigure's current values, the printed
effective configuration), a typo key is warned about with the nearest key, and a node given an
out-of-range value, an unknown model set or a bogus odometry source refuses to start, naming the
key."""
import os
import shutil
import subprocess
import tempfile
import time
import unittest

import rospy
import rostest
import yaml
from dynamic_reconfigure.client import Client
from geofusion.msg import ObjectMap
from geofusion.srv import SaveMap
from std_srvs.srv import Trigger

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
        client = Client(NS, timeout=10)
        self.wait_for(lambda: abs(client.get_configuration(timeout=10)['eps_fp'] - 0.5) < 1e-9, 5)
        current = client.get_configuration(timeout=10)
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
        self.assertIn('[0.001, 1]', log)
        code, log = self.run_node('_model_set:=no_such_models')
        self.assertNotEqual(code, 0, log)
        self.assertIn("unknown model set 'no_such_models'", log)
        code, log = self.run_node('_odometry:=bogus')
        self.assertNotEqual(code, 0, log)
        self.assertIn('expected tf, topic or visual', log)

    def test_4_run_offline_reproduces_the_node_from_its_saved_configuration(self):
        """The saved map says how it was made; run_offline --params with that reproduces it."""
        d = tempfile.mkdtemp(prefix='geofusion_config_')
        try:
            subprocess.check_call([util.find_tool('generate_dataset'), '--suite', 'demo',
                                   '--out-dir', d, '--keyframes', '16', '--previews', '0'],
                                  stdout=subprocess.DEVNULL)
            bag = os.path.join(d, 'demo_01.bag')
            self.assertTrue(util.wait_for_graph(util.INPUT_TOPICS, [NS + '/object_map']))
            rospy.ServiceProxy(NS + '/reset', Trigger)()
            util.play(bag, rate=0.5)
            time.sleep(2.0)
            rospy.wait_for_service(NS + '/save_map', 5.0)
            self.assertTrue(rospy.ServiceProxy(NS + '/save_map', SaveMap)(
                os.path.join(d, 'node')).success)
            node = util.load_yaml(os.path.join(d, 'node.yaml'))
            with open(os.path.join(d, 'config.yaml'), 'w') as f:
                yaml.safe_dump(node['config'], f)
            subprocess.check_call([util.find_tool('run_offline'), '--bag', bag, '--out',
                                   os.path.join(d, 'offline.yaml'), '--params',
                                   os.path.join(d, 'config.yaml'), '--quiet'],
                                  stdout=subprocess.DEVNULL)
            offline = util.load_yaml(os.path.join(d, 'offline.yaml'))
            self.assertEqual(offline['config'], node['config'])
            self.assertEqual(len(node['trajectory']), 16, 'the node skipped a keyframe')
            self.assertEqual(len(offline['trajectory']), 16)
            a, b = node['final_map']['objects'], offline['final_map']['objects']
            self.assertEqual([o['class_name'] for o in a], [o['class_name'] for o in b])
            worst = max(abs(x - y) for oa, ob in zip(a, b)
                        for x, y in zip(oa['map_object'], ob['map_object']))
            print('node vs run_offline: %d objects, largest pose difference %.2e' % (len(a), worst))
            self.assertLess(worst, 1e-6)
            self.assertEqual(len(node['final_map']['contacts']),
                             len(offline['final_map']['contacts']))
        finally:
            shutil.rmtree(d, ignore_errors=True)

    def test_5_initial_map_continues_a_saved_map_or_refuses_to_start(self):
        """~initial_map: a plain node started with a saved map publishes it (same ids, classes
        and poses) before any input; a map that cannot be loaded stops the start with why."""
        d = tempfile.mkdtemp(prefix='geofusion_initial_map_')
        try:
            util.generate_demo(d, 12)
            prefix = os.path.join(d, 'saved')
            subprocess.check_call([util.find_tool('run_offline'), '--bag',
                                   os.path.join(d, 'demo_01.bag'), '--out',
                                   os.path.join(d, 'offline.yaml'), '--model-set', 'primitives',
                                   '--save-map', prefix, '--quiet'], stdout=subprocess.DEVNULL)
            saved = util.load_yaml(prefix + '.yaml')['final_map']['objects']
            self.assertGreater(len(saved), 0)
            name = 'resumed_%d' % int(time.time() * 1000)
            maps = []
            sub = rospy.Subscriber('/%s/object_map' % name, ObjectMap, maps.append, queue_size=10)
            node = subprocess.Popen([util.find_tool('scene_estimator_node'), '__name:=' + name,
                                     '_model_set:=primitives', '_initial_map:=' + prefix],
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            try:
                self.assertTrue(self.wait_for(lambda: maps, timeout_s=60),
                                'no map from a node started with ~initial_map')
            finally:
                node.terminate()
                log = node.communicate(timeout=30)[0]
                sub.unregister()
            # Message ids are the map's plus one (0 is the table, MapObject.msg).
            got = sorted((o.id, o.class_name) for o in maps[0].objects)
            self.assertEqual(got, sorted((o['id'] + 1, o['class_name']) for o in saved), log)
            self.assertNotIn('initial_map is not read by anything', log)
            by_id = {o.id: o for o in maps[0].objects}
            for o in saved:
                p = by_id[o['id'] + 1].pose.pose.position
                self.assertAlmostEqual(p.x, o['map_object'][0], places=6)
                self.assertAlmostEqual(p.y, o['map_object'][1], places=6)
                self.assertAlmostEqual(p.z, o['map_object'][2], places=6)
            code, log = self.run_node('_model_set:=primitives',
                                      '_initial_map:=' + os.path.join(d, 'no_such_map'))
            self.assertNotEqual(code, 0, log)
            self.assertIn('~initial_map:', log)
            self.assertIn('not starting', log)
        finally:
            shutil.rmtree(d, ignore_errors=True)


if __name__ == '__main__':
    rospy.init_node('config_checker')
    rostest.rosrun('geofusion', 'config_checker', ConfigTest)
