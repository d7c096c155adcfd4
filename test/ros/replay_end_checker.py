#!/usr/bin/python3
"""replay.launch ends cleanly when the recording ends (issue 33): roslaunch on a short generated
recording at 4x exits 0 on its own, the estimator made keyframes, and no process is reported dead
("REQUIRED process has died", "process has died"): the player shuts the launch down as Ctrl-C
would. roslaunch runs its own master on a free port."""
import os
import socket
import subprocess
import unittest

import geofusion_test_utils as util


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


class ReplayEndsCleanly(unittest.TestCase):
    def test_replay_launch_ends_with_the_recording(self):
        out = util.tempfile.mkdtemp(prefix='geofusion_replay_end_')
        bag = util.generate_demo(out, 12)
        env = dict(os.environ, ROS_HOME=os.path.join(out, 'ros'))
        run = subprocess.run(['roslaunch', '-p', str(free_port()), 'geofusion', 'replay.launch',
                              'bag:=' + bag, 'rate:=4', 'delay:=2', 'model_set:=primitives'],
                             env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                             timeout=240)
        log = run.stdout
        self.assertEqual(run.returncode, 0, log[-3000:])
        self.assertNotIn('has died', log, log[-3000:])
        self.assertIn('scene estimator (GeoFusion', log, 'the estimator did not start')
        self.assertIn('the recording has been played to its end; stopping the launch', log)
        self.assertIn('shutting down', log.lower(), log[-3000:])


if __name__ == '__main__':
    unittest.main()
