#!/usr/bin/python3
"""rosbag play for the launch files: plays a recording and, with --stop-at-end, ends the launch
the way Ctrl-C would once the recording has been played (roslaunch's required="true" ends it
too, but with a red "REQUIRED process [player] has died!" for a player that finished cleanly).

    play_recording.py [--stop-at-end] ROSBAG_PLAY_ARGS...

A player that fails (a missing or unreadable bag) is reported with its exit code and, with
--stop-at-end, ends the launch too, so that it never waits for a recording that will not come.
"""
import os
import signal
import subprocess
import sys


def main():
    # roslaunch appends __name:= and __log:= remappings; rosbag play takes neither.
    args = [a for a in sys.argv[1:] if not a.startswith('__')]
    stop_at_end = '--stop-at-end' in args
    args = [a for a in args if a != '--stop-at-end']
    player = subprocess.Popen(['rosbag', 'play'] + args)
    stopping = []

    def forward(signum, _frame):  # the launch is ending: the player ends with it
        stopping.append(signum)
        player.send_signal(signal.SIGINT)

    signal.signal(signal.SIGINT, forward)
    signal.signal(signal.SIGTERM, forward)
    code = player.wait()
    if stopping:
        return 0
    if code == 0:
        print('[geofusion] the recording has been played to its end' +
              ('; stopping the launch' if stop_at_end else ''), flush=True)
    else:
        print('[geofusion] rosbag play failed (exit code %d)%s' %
              (code, '; stopping the launch' if stop_at_end else ''), file=sys.stderr, flush=True)
    if stop_at_end:
        os.kill(os.getppid(), signal.SIGINT)  # roslaunch: a clean shutdown, as on Ctrl-C
    return 0 if code == 0 else 1


if __name__ == '__main__':
    sys.exit(main())
