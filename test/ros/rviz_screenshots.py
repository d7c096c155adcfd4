#!/usr/bin/python3
"""Runs test/ros/rviz_screenshots.test under a virtual display (Xvfb): rviz with
rviz/geofusion.rviz, the map panel plugin and the estimator on the demo recording; the checker
takes the screenshots of README and docs/running.md. GEOFUSION_SCREENSHOT_DIR: where they go (`make screenshots`
writes docs/images; default a temporary folder). Exit code: rostest's."""
import os
import subprocess
import sys
import tempfile
import time


def free_display():
    for n in range(91, 140):
        if not os.path.exists('/tmp/.X%d-lock' % n) and \
           not os.path.exists('/tmp/.X11-unix/X%d' % n):
            return n
    raise RuntimeError('no free X display number between :91 and :139')


def main():
    out = os.environ.get('GEOFUSION_SCREENSHOT_DIR') or tempfile.mkdtemp(prefix='geofusion_shots_')
    os.makedirs(out, exist_ok=True)
    n = free_display()
    xvfb = subprocess.Popen(['Xvfb', ':%d' % n, '-screen', '0', '1400x1000x24', '-nolisten', 'tcp'],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(50):
            if os.path.exists('/tmp/.X11-unix/X%d' % n):
                break
            time.sleep(0.1)
        env = dict(os.environ, DISPLAY=':%d' % n, GEOFUSION_SCREENSHOT_DIR=out)
        rc = subprocess.call(['rostest', 'geofusion', 'rviz_screenshots.test'] + sys.argv[1:],
                             env=env)
        print('rviz_screenshots: screenshots in %s' % out)
        return rc
    finally:
        xvfb.terminate()
        xvfb.wait()


if __name__ == '__main__':
    sys.exit(main())
