#!/usr/bin/python3
"""Runs test/ros/rviz_screenshots.test under a virtual display (Xvfb): rviz with
rviz/geofusion.rviz, the map panel plugin and the estimator on the demo recording; the checker
takes the screenshots of README and docs/running.md. GEOFUSION_SCREENSHOT_DIR: where they go (`make screenshots`
writes docs/images; default a temporary folder). Exit code: rostest's."""
import os
import subprocess
import sys
import tempfile


def start_xvfb():
    """Xvfb on a display it finds free itself (-displayfd: it tries the numbers up from :0 and
    says which one it took), so that runs in two chroots, which share the machine's abstract X
    sockets but not /tmp, never pick the same number; returns (process, display number)."""
    read_end, write_end = os.pipe()
    xvfb = subprocess.Popen(['Xvfb', '-displayfd', str(write_end), '-screen', '0', '1400x1000x24',
                             '-nolisten', 'tcp'], pass_fds=(write_end,),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write_end)
    with os.fdopen(read_end) as f:
        line = f.readline().strip()
    if not line.isdigit():
        xvfb.kill()
        raise RuntimeError('Xvfb did not start (no display number from -displayfd)')
    return xvfb, int(line)


def main():
    out = os.environ.get('GEOFUSION_SCREENSHOT_DIR') or tempfile.mkdtemp(prefix='geofusion_shots_')
    os.makedirs(out, exist_ok=True)
    xvfb, n = start_xvfb()
    try:
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
