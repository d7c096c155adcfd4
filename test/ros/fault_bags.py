"""Recordings with one deliberate fault each, made from a good recording with python rosbag (the
tests' inputs for issue 21's hardening; imported by the checkers, not run)."""
import copy
import random

DETECTIONS = '/detections'


def _copy(src_path, out_path, change):
    """Copies src to out; change(topic, msg, t) returns a list of (topic, msg, t) to write."""
    import rosbag
    with rosbag.Bag(src_path) as src, rosbag.Bag(out_path, 'w') as dst:
        for topic, msg, t in src.read_messages():
            for item in change(topic, msg, t):
                dst.write(*item)


def _recording_start(src_path):
    import rosbag
    with rosbag.Bag(src_path) as src:
        return src.get_start_time(), src.get_end_time()


def tf_gap(src_path, out_path, start_fraction=0.4, length_s=2.0, odom_frame='odom'):
    """The odom -> base transforms removed for `length_s` seconds from `start_fraction` of the
    recording: a robot whose odometry stalled. Returns (gap start, gap end) in stamps."""
    begin, end = _recording_start(src_path)
    g0 = begin + start_fraction * (end - begin)
    g1 = g0 + length_s

    def change(topic, msg, t):
        if topic == '/tf':
            msg.transforms = [x for x in msg.transforms
                              if not (x.header.frame_id == odom_frame and
                                      g0 <= x.header.stamp.to_sec() < g1)]
            if not msg.transforms:
                return []
        return [(topic, msg, t)]
    _copy(src_path, out_path, change)
    return g0, g1


def late_detections(src_path, out_path, every=3, delay_s=0.45):
    """Every `every`-th detection message written `delay_s` later than its stamp (after those of
    later frames): detections arriving out of order. Returns how many were delayed."""
    import rosbag
    import rospy
    items, delayed, n = [], 0, 0
    with rosbag.Bag(src_path) as src:
        for topic, msg, t in src.read_messages():
            if topic.endswith(DETECTIONS):
                n += 1
                if n % every == 0:
                    t = t + rospy.Duration(delay_s)
                    delayed += 1
            items.append((topic, msg, t))
    items.sort(key=lambda x: x[2].to_nsec())
    with rosbag.Bag(out_path, 'w') as dst:
        for item in items:
            dst.write(*item)
    return delayed


def flooded_detections(src_path, out_path, frame=5, count=5000, seed=1):
    """Detection message number `frame` replaced by `count` detections (copies of its own with
    random scores and small offsets): a detector gone wild. Returns its stamp."""
    rng = random.Random(seed)
    state = {'n': 0, 'stamp': None}

    def change(topic, msg, t):
        if topic.endswith(DETECTIONS):
            state['n'] += 1
            if state['n'] == frame and msg.detections:
                state['stamp'] = msg.header.stamp.to_sec()
                base = msg.detections
                flood = []
                for i in range(count):
                    d = copy.deepcopy(base[i % len(base)])
                    d.score = rng.uniform(0.05, 0.95)
                    d.pose.position.x += rng.uniform(-0.01, 0.01)
                    flood.append(d)
                msg.detections = flood
        return [(topic, msg, t)]
    _copy(src_path, out_path, change)
    return state['stamp']


def unknown_classes(src_path, out_path, every=4, name='999_not_in_the_model_set'):
    """Every `every`-th detection renamed to a class no model set has. Returns how many."""
    state = {'n': 0, 'renamed': 0}

    def change(topic, msg, t):
        if topic.endswith(DETECTIONS):
            for d in msg.detections:
                state['n'] += 1
                if state['n'] % every == 0:
                    d.class_name = name
                    state['renamed'] += 1
        return [(topic, msg, t)]
    _copy(src_path, out_path, change)
    return state['renamed']


def shifted_detection_stamps(src_path, out_path, shift_s=0.5):
    """Every detection stamped `shift_s` later than its images: stamps that never match."""
    import rospy

    def change(topic, msg, t):
        if topic.endswith(DETECTIONS):
            msg.header.stamp = msg.header.stamp + rospy.Duration(shift_s)
        return [(topic, msg, t)]
    _copy(src_path, out_path, change)


def odometry_starts_late(src_path, out_path, delay_s=1.0, odom_frame='odom'):
    """The odom -> base transforms of the first `delay_s` seconds removed: a robot whose
    odometry comes up after the camera (no camera pose for those frames, not a gap). Returns the
    stamp of the first transform kept."""
    begin, _ = _recording_start(src_path)
    first = begin + delay_s

    def change(topic, msg, t):
        if topic == '/tf':
            msg.transforms = [x for x in msg.transforms
                              if not (x.header.frame_id == odom_frame and
                                      x.header.stamp.to_sec() < first)]
            if not msg.transforms:
                return []
        return [(topic, msg, t)]
    _copy(src_path, out_path, change)
    return first


def broken_depth(src_path, out_path, every=4):
    """Every `every`-th depth image cut to half its bytes (a driver that sent a partial frame):
    unusable depth. Returns how many."""
    state = {'n': 0, 'broken': 0}

    def change(topic, msg, t):
        if 'depth' in topic and msg._type == 'sensor_msgs/Image':
            state['n'] += 1
            if state['n'] % every == 0:
                msg.data = msg.data[:len(msg.data) // 2]
                state['broken'] += 1
        return [(topic, msg, t)]
    _copy(src_path, out_path, change)
    return state['broken']


def truncated(src_path, out_path, fraction=0.6):
    """The first `fraction` of the file's bytes: a recording killed before it closed."""
    with open(src_path, 'rb') as f:
        data = f.read()
    with open(out_path, 'wb') as f:
        f.write(data[:int(len(data) * fraction)])
