"""Helpers shared by the package's rostest checkers (imported, not run)."""
import math
import os
import subprocess
import tempfile
import time

import rosgraph
import roslib.packages
import yaml


def find_tool(name):
    paths = roslib.packages.find_node('geofusion', name)
    if not paths:
        raise RuntimeError('cannot find the geofusion executable %s (is the package built?)' % name)
    return paths[0]


def make_bag(name, *args):
    """Writes a synthetic bag with make_synthetic_bag; returns (bag, ground truth)."""
    out_dir = tempfile.mkdtemp(prefix='geofusion_test_')
    bag = os.path.join(out_dir, name + '.bag')
    subprocess.check_call([find_tool('make_synthetic_bag'), '--out', bag] +
                          [str(a) for a in args])
    with open(bag[:-4] + '_gt.yaml') as f:
        gt = yaml.safe_load(f)
    return bag, gt


def generate_demo(out_dir, keyframes, extra=()):
    """Generates the demo suite's recording into out_dir (`extra`: more generate_dataset
    arguments); returns the path of demo_01.bag."""
    subprocess.check_call([find_tool('generate_dataset'), '--suite', 'demo', '--out-dir', out_dir,
                           '--keyframes', str(keyframes), '--previews', '0'] + list(extra),
                          stdout=subprocess.DEVNULL)
    return os.path.join(out_dir, 'demo_01.bag')


def wait_for_graph(subscribed_topics, published_topics, timeout_s=30.0):
    """Waits (wall time) until every topic has a subscriber / publisher registered."""
    master = rosgraph.Master('/geofusion_test')
    deadline = time.time() + timeout_s
    while time.time() < deadline:
        pubs, subs, _ = master.getSystemState()
        pub_topics = {t for t, _ in pubs}
        sub_topics = {t for t, _ in subs}
        if all(t in sub_topics for t in subscribed_topics) and \
           all(t in pub_topics for t in published_topics):
            return True
        time.sleep(0.2)
    return False


def wait_until(condition, timeout_s=15.0, poll_s=0.1):
    """Waits (wall time) until condition() is true or timeout_s passed; returns condition().
    For what arrives after a replay ends: a process that is slower than usual (an instrumented
    build, a loaded machine) delivers late, not less."""
    deadline = time.time() + timeout_s
    while time.time() < deadline and not condition():
        time.sleep(poll_s)
    return condition()


def test_slowdown():
    """GEOFUSION_TEST_SLOWDOWN: how many times slower scripts/test_sanitizer.sh's instrumented
    build runs (1 otherwise)."""
    return float(os.environ.get('GEOFUSION_TEST_SLOWDOWN', '1'))


def throughput_rate(rate):
    """The replay rate for a test whose pass depends on how fast the code runs (the estimator must
    keep up, or fall behind by a bounded amount): rate divided by GEOFUSION_TEST_SLOWDOWN, which
    scripts/test_sanitizer.sh sets for its instrumented build (several times slower); 1 otherwise."""
    return rate / test_slowdown()


def play(bag, rate=1.0):
    """Plays a bag with --clock (the tests run with /use_sim_time) and waits for the end."""
    subprocess.check_call(['rosbag', 'play', '--clock', '-q', '-d', '1', '-r', str(rate), bag])


def play_async(bag, rate=1.0):
    """Starts playing a bag with --clock; returns the process (wait() for the end)."""
    return subprocess.Popen(['rosbag', 'play', '--clock', '-q', '-d', '1', '-r', str(rate), bag],
                            stdout=subprocess.DEVNULL)


def strip_tf(bag, out, parent):
    """Copies a recording without the /tf transforms whose parent is `parent` (as a robot whose
    odometry is not on TF); returns how many transforms were dropped."""
    import rosbag
    dropped = 0
    with rosbag.Bag(bag) as src, rosbag.Bag(out, 'w') as dst:
        for topic, msg, t in src.read_messages():
            if topic == '/tf':
                kept = [x for x in msg.transforms if x.header.frame_id != parent]
                dropped += len(msg.transforms) - len(kept)
                msg.transforms = kept
            dst.write(topic, msg, t)
    return dropped


def match_objects(objects, gt, tolerance_m, frame=None):
    """Greedy class-aware matching of geofusion/MapObject messages to the ground truth's objects
    by position; returns (matched ground-truth indices, number of unmatched estimates). `frame`:
    the estimate's frame in the ground truth's, [x, y, z, qx, qy, qz, qw] (default: the same)."""
    truth = [(o['class_name'], o['pose'][:3]) for o in gt['objects']]
    x, y, z, qx, qy, qz, qw = frame if frame else (0, 0, 0, 0, 0, 0, 1)
    R = rotation(qx, qy, qz, qw)
    matched, false = set(), 0
    for o in objects:
        q = (o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z)
        p = tuple(sum(R[i][k] * q[k] for k in range(3)) + (x, y, z)[i] for i in range(3))
        best, best_i = 1e9, -1
        for i, (name, q) in enumerate(truth):
            if name == o.class_name and i not in matched and math.dist(p, q) < best:
                best, best_i = math.dist(p, q), i
        if best < tolerance_m:
            matched.add(best_i)
        else:
            false += 1
    return matched, false


def _robot_names():
    """The robot's topic and frame names (config/robots/fetch.yaml, the one place they live)."""
    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'config',
                           'robots', 'fetch.yaml')) as f:
        return yaml.safe_load(f)


ROBOT = _robot_names()
RGB_TOPIC = '/' + ROBOT['rgb_topic']
DEPTH_TOPIC = '/' + ROBOT['depth_topic']
CAMERA_INFO_TOPIC = '/' + ROBOT['camera_info_topic']
DETECTIONS_TOPIC = '/' + ROBOT['detections_topic']
ODOM_TOPIC = '/' + ROBOT['wheel_odom_topic']
ODOM_FRAME = ROBOT['odom_frame']
BASE_FRAME = ROBOT['base_frame']
CAMERA_LINK_FRAME = ROBOT['camera_link_frame']
CAMERA_FRAME = ROBOT['camera_frame']
INPUT_TOPICS = [RGB_TOPIC, DEPTH_TOPIC, CAMERA_INFO_TOPIC, DETECTIONS_TOPIC]


def load_yaml(path):
    """A (possibly large) YAML file, with the C loader when there is one."""
    with open(path) as f:
        return yaml.load(f, Loader=getattr(yaml, 'CSafeLoader', yaml.SafeLoader))


def rotation(qx, qy, qz, qw):
    """3x3 rotation matrix (nested lists) of a unit quaternion."""
    x, y, z, w = qx, qy, qz, qw
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
