#!/usr/bin/python3
"""Live benchmark (make live-bench, docs/BENCHMARK.md "Live"): the robot's launch
(replay.launch: geofusion.launch in a nodelet manager, fed by rosbag play --clock) on one
recording at one rate, as a robot runs it, with the other core idle or busy.

    live_bench.py --bag BAG --rate R [--load] [--odometry tf|visual] [--launch-arg k:=v ...]
                  --out RUN.json

Measured in wall time, per frame, from the moment the frame's camera_info reaches this process
(rosbag play publishes it beside the images) to the arrival of the ObjectMap stamped with that
frame's stamp, and of its object_<id> TF frames; frames sent and maps received; the estimator's
own drop counts by reason (its diagnostics); the nodelet manager's CPU share
(/proc/<pid>/stat). With --load a busy process runs beside it for the whole run.
"""
import argparse
import json
import os
import signal
import subprocess
import sys
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray
from sensor_msgs.msg import CameraInfo
from tf2_msgs.msg import TFMessage

from geofusion.msg import DetectionArray, ObjectMap


def percentile(values, p):
    if not values:
        return None
    v = sorted(values)
    return v[min(len(v) - 1, int(round(p * (len(v) - 1))))]


def cpu_seconds(pid):
    with open('/proc/%d/stat' % pid) as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def find_pid(pattern, timeout_s=30.0):
    end = time.time() + timeout_s
    while time.time() < end:
        out = subprocess.run(['pgrep', '-f', pattern], capture_output=True, text=True).stdout
        pids = [int(p) for p in out.split()]
        if pids:
            return pids[0]
        time.sleep(0.2)
    return None


class Recorder:
    def __init__(self, frame_prefix):
        self.lock = threading.Lock()
        self.info_wall = {}   # stamp (ns) -> wall time the frame's camera_info arrived
        self.dets_wall = {}   # stamp (ns) -> wall time its detections arrived (the last input)
        self.map_wall = {}    # stamp (ns) -> wall time its ObjectMap arrived
        self.tf_wall = {}     # stamp (ns) -> wall time its first object frame arrived
        self.map_objects = {}
        self.drops = {}
        self.diag = {}
        self.frame_prefix = frame_prefix

    def on_info(self, msg):
        with self.lock:
            self.info_wall.setdefault(msg.header.stamp.to_nsec(), time.time())

    def on_dets(self, msg):
        with self.lock:
            self.dets_wall.setdefault(msg.header.stamp.to_nsec(), time.time())

    def on_map(self, msg):
        with self.lock:
            key = msg.header.stamp.to_nsec()
            self.map_wall.setdefault(key, time.time())
            self.map_objects[key] = len(msg.objects)

    def on_tf(self, msg):
        now = time.time()
        with self.lock:
            for t in msg.transforms:
                if t.child_frame_id.startswith(self.frame_prefix):
                    self.tf_wall.setdefault(t.header.stamp.to_nsec(), now)

    def on_diag(self, msg):
        with self.lock:
            for status in msg.status:
                if status.name.endswith('scene estimator'):
                    self.diag = {kv.key: kv.value for kv in status.values}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--bag', required=True)
    ap.add_argument('--rate', type=float, default=1.0)
    ap.add_argument('--load', action='store_true', help='a busy process beside it')
    ap.add_argument('--odometry', default='tf')
    ap.add_argument('--launch-arg', action='append', default=[])
    ap.add_argument('--out', required=True)
    ap.add_argument('--camera-info-topic', default='/head_camera/rgb/camera_info')
    ap.add_argument('--map-topic', default='/scene_estimator/object_map')
    ap.add_argument('--detections-topic', default='/detections')
    ap.add_argument('--delay', type=float, default=10.0,
                    help='seconds between the launch and the first message')
    ap.add_argument('--port', type=int, default=11471, help="the run's own ROS master")
    a = ap.parse_args()
    os.environ['ROS_MASTER_URI'] = 'http://localhost:%d' % a.port

    busy = None
    if a.load:
        busy = subprocess.Popen([sys.executable, '-c', 'while True: pass'])
    launch = subprocess.Popen(
        ['roslaunch', '--skip-log-check', '-p', str(a.port), 'geofusion', 'replay.launch', 'bag:=' + a.bag,
         'rate:=%g' % a.rate, 'odometry:=' + a.odometry, 'stop_at_end:=false',
         # A robot's estimator is up before its data: every model set loads well within this.
         'delay:=%g' % a.delay] + a.launch_arg,
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    rec = Recorder('object_')
    result = {'bag': a.bag, 'rate': a.rate, 'load': a.load, 'odometry': a.odometry,
              'launch_args': a.launch_arg}
    try:
        # The player waits --delay s before the first message: subscribe before it starts.
        time.sleep(1.0)
        rospy.init_node('live_bench', anonymous=True, disable_signals=True)
        rospy.Subscriber(a.camera_info_topic, CameraInfo, rec.on_info, queue_size=1000)
        rospy.Subscriber(a.map_topic, ObjectMap, rec.on_map, queue_size=1000)
        rospy.Subscriber(a.detections_topic, DetectionArray, rec.on_dets, queue_size=1000)
        rospy.Subscriber('/tf', TFMessage, rec.on_tf, queue_size=10000)
        rospy.Subscriber('/diagnostics', DiagnosticArray, rec.on_diag, queue_size=100)
        manager = find_pid('__name:=geofusion_manager')
        player = find_pid('play_recording.py')
        cpu0, wall0 = (cpu_seconds(manager), time.time()) if manager else (None, None)
        # Until the player has played the recording, then until the maps stop coming.
        while player and os.path.exists('/proc/%d' % player):
            time.sleep(0.2)
        last = -1
        while True:
            time.sleep(2.0)
            with rec.lock:
                n = len(rec.map_wall)
            if n == last:
                break
            last = n
        time.sleep(1.5)  # one more diagnostics message
        if manager and os.path.exists('/proc/%d' % manager):
            result['manager_cpu_percent'] = \
                100.0 * (cpu_seconds(manager) - cpu0) / (time.time() - wall0)
    finally:
        os.killpg(launch.pid, signal.SIGINT)
        try:
            launch.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(launch.pid, signal.SIGKILL)
        if busy:
            busy.kill()
    with rec.lock:
        frames = sorted(rec.info_wall)
        maps = sorted(k for k in rec.map_wall if k in rec.info_wall)
        first = maps[0] if maps else None
        lat = [1e3 * (rec.map_wall[k] - rec.info_wall[k]) for k in maps]
        tf_lat = [1e3 * (rec.tf_wall[k] - rec.info_wall[k]) for k in maps if k in rec.tf_wall]
        # GeoFusion's own share: from the last input of the set (the detections, which a
        # detector publishes after the image; the recordings delay them 0.1 s) to the map.
        own = [1e3 * (rec.map_wall[k] - rec.dets_wall[k]) for k in maps if k in rec.dets_wall]
        # From the first keyframe on: frames after it that gave no map.
        later = [k for k in frames if first is not None and k >= first]
        result.update({
            'frames_sent': len(frames),
            'maps_received': len(maps),
            'frames_without_map_after_first': len([k for k in later if k not in rec.map_wall]),
            'latency_ms': {'p50': percentile(lat, 0.5), 'p95': percentile(lat, 0.95),
                           'max': max(lat) if lat else None},
            'latency_ms_after_first': {'p95': percentile(lat[1:], 0.95),
                                       'max': max(lat[1:]) if len(lat) > 1 else None},
            'first_map_latency_ms': lat[0] if lat else None,
            'own_latency_ms': {'p50': percentile(own, 0.5), 'p95': percentile(own, 0.95),
                               'max': max(own) if own else None},
            'tf_latency_ms': {'p50': percentile(tf_lat, 0.5), 'p95': percentile(tf_lat, 0.95),
                              'max': max(tf_lat) if tf_lat else None},
            'latency_series_ms': lat,
            'diagnostics': {k: v for k, v in rec.diag.items()
                            if k.startswith('frames dropped') or k.startswith('background')
                            or k in ('synchronised frames', 'keyframes',
                                     'keyframes over the time budget')},
        })
    with open(a.out, 'w') as f:
        json.dump(result, f, indent=1)
    print('live_bench: %s at %gx%s: %d frames, %d maps, latency p50/p95/max %s/%s/%s ms, '
          'manager %.0f %% of a core' % (
              os.path.basename(a.bag), a.rate, ' (loaded)' if a.load else '', len(frames),
              len(maps), *['%.0f' % x if x is not None else '-' for x in
                           (result['latency_ms']['p50'], result['latency_ms']['p95'],
                            result['latency_ms']['max'])],
              result.get('manager_cpu_percent', float('nan'))))
    return 0 if maps else 1


if __name__ == '__main__':
    sys.exit(main())
