#!/usr/bin/python3
"""validate_bag.py: says what is wrong with a recording before GeoFusion is run on it.

    validate_bag.py BAG [--rgb-topic T] [--depth-topic T] [--camera-info-topic T]
        [--detections-topic T] [--odom-topic T] [--odom-frame F] [--base-frame F]
        [--max-sync-spread S] [--quiet]

Reads the bag once, streaming (one message in memory at a time), and prints one finding a line:
`ERROR:` (the estimator cannot use the recording, or loses every frame to it), `WARNING:` (some
frames or detections will be skipped, or something looks suspicious) or `OK:` (what was checked
and found fine, with counts and rates; left out with --quiet), then a `SUMMARY:` line.
A problem that affects every message of a required topic is an ERROR, one that affects only some
of them a WARNING (those frames are skipped).

Times are header stamps in seconds, followed by their offset from the first RGB image stamp.

Exit code: 0 no errors (warnings allowed), 1 errors, 2 usage problem or unreadable bag.
"""
import argparse
import bisect
import collections
import math
import os
import struct
import sys

import genpy
import rosbag
import yaml

EXIT_OK, EXIT_ERRORS, EXIT_USAGE = 0, 1, 2

RGB_ENCODINGS = ('rgb8', 'bgr8', 'mono8', 'rgba8', 'bgra8')
DEPTH_ENCODINGS = ('32FC1', '16UC1')
BYTES_PER_PIXEL = {'rgb8': 3, 'bgr8': 3, 'mono8': 1, 'rgba8': 4, 'bgra8': 4, 'mono16': 2,
                   '32FC1': 4, '16UC1': 2}
TF_TOPIC, TF_STATIC_TOPIC = '/tf', '/tf_static'
TF_TYPES = ('tf2_msgs/TFMessage', 'tf/tfMessage')
QUATERNION_TOLERANCE = 1e-3      # | |q| - 1 | above this: not a unit quaternion (as the estimator)
MAX_RECEIVE_DELAY_S = 1.0        # header stamp vs bag receive time
TF_GAP_S = 1.0                   # dynamic TF silent this long while images come: reported
TF_EDGE_TOLERANCE_S = 0.1        # images this far before the first / after the last transform
# A detection is computed from an image the perception stack has already received, so the image
# it is synchronised with cannot have been recorded much later than the detection itself.
CAUSAL_TOLERANCE_S = 0.25
MAX_EXAMPLES = 3


# ----------------------------------------------------------------------------------------------
# Report

class Report:
    def __init__(self, quiet):
        self.quiet = quiet
        self.lines = []
        self.errors = 0
        self.warnings = 0

    def error(self, subject, text):
        self.errors += 1
        self.lines.append('ERROR: %s: %s' % (subject, text))

    def warning(self, subject, text):
        self.warnings += 1
        self.lines.append('WARNING: %s: %s' % (subject, text))

    def ok(self, subject, text):
        if not self.quiet:
            self.lines.append('OK: %s: %s' % (subject, text))

    def problem(self, bad, total, subject, text):
        """ERROR when every message is affected (nothing usable), WARNING when only some are."""
        if bad >= total:
            self.error(subject, text)
        else:
            self.warning(subject, text)

    def print(self, out=sys.stdout):
        for line in self.lines:
            out.write(line + '\n')
        out.flush()


def plural(n, word, words=None):
    return '%d %s' % (n, word if n == 1 else (words or word + 's'))


def examples(items):
    items = list(items)
    text = '; '.join(str(i) for i in items[:MAX_EXAMPLES])
    return text + ('; ...' if len(items) > MAX_EXAMPLES else '')


class Clock:
    """Formats header stamps as 'seconds (+offset from the first RGB image stamp)'."""

    def __init__(self):
        self.ref = None

    def __call__(self, stamp):
        if self.ref is None:
            return '%.3f' % stamp
        return '%.3f (%+.2f s)' % (stamp, stamp - self.ref)


# ----------------------------------------------------------------------------------------------
# What is gathered while streaming through the bag

class TopicStats:
    """Per topic: message types, counts, receive times, header stamps and frames."""

    def __init__(self, topic, expected_types):
        self.topic = topic
        self.expected_types = expected_types
        self.types = collections.Counter()
        self.count = 0                   # messages of an expected type
        self.first_rec = self.last_rec = None
        self.prev_stamp = None
        self.zero_stamps = 0
        self.backwards = []              # (index, previous stamp, stamp, receive time)
        self.repeated = 0
        self.late = 0                    # |header stamp - receive time| > MAX_RECEIVE_DELAY_S
        self.max_delay = 0.0
        self.frames = collections.Counter()

    def accepts(self, msg_type):
        self.types[msg_type] += 1
        return msg_type in self.expected_types

    def add(self, stamp, rec, frame_id=None):
        index = self.count
        self.count += 1
        if self.first_rec is None:
            self.first_rec = rec
        self.last_rec = rec
        if frame_id is not None:
            self.frames[frame_id] += 1
        if stamp == 0.0:
            self.zero_stamps += 1
            return index
        delay = rec - stamp
        if abs(delay) > MAX_RECEIVE_DELAY_S:
            self.late += 1
            if abs(delay) > abs(self.max_delay):
                self.max_delay = delay
        if self.prev_stamp is not None:
            if stamp < self.prev_stamp:
                self.backwards.append((index, self.prev_stamp, stamp, rec))
            elif stamp == self.prev_stamp:
                self.repeated += 1
        self.prev_stamp = stamp
        return index

    def rate_hz(self):
        if self.count < 2 or self.last_rec <= self.first_rec:
            return None
        return (self.count - 1) / (self.last_rec - self.first_rec)


class ImageStats(TopicStats):
    def __init__(self, topic):
        TopicStats.__init__(self, topic, ('sensor_msgs/Image',))
        self.encodings = collections.Counter()
        self.sizes = collections.Counter()
        self.empty = []                  # (index, why)
        self.big_endian = 0
        self.stamps = []                 # (header stamp, receive time), receive order; no zeros

    def add_image(self, msg, rec):
        stamp = msg.header.stamp.to_sec()
        index = self.add(stamp, rec, msg.header.frame_id)
        if stamp != 0.0:
            self.stamps.append((stamp, rec))
        self.encodings[msg.encoding] += 1
        self.sizes[(msg.width, msg.height)] += 1
        if msg.is_bigendian:
            self.big_endian += 1
        why = image_defect(msg)
        if why:
            self.empty.append((index, why))


class CameraInfoStats(TopicStats):
    def __init__(self, topic):
        TopicStats.__init__(self, topic, ('sensor_msgs/CameraInfo',))
        self.sizes = collections.Counter()
        self.bad_focal = []              # (index, fx, fy)
        self.bad_lens = []               # (index, why): a distortion the estimator cannot rectify
        self.lenses = collections.Counter()
        self.stamps = []

    def add_info(self, msg, rec):
        stamp = msg.header.stamp.to_sec()
        index = self.add(stamp, rec, msg.header.frame_id)
        if stamp != 0.0:
            self.stamps.append(stamp)
        self.sizes[(msg.width, msg.height)] += 1
        fx, fy = msg.K[0], msg.K[4]
        if not (math.isfinite(fx) and math.isfinite(fy)) or fx == 0.0 or fy == 0.0:
            self.bad_focal.append((index, fx, fy))
        why = lens_problem(msg.distortion_model, list(msg.D))
        if why:
            self.bad_lens.append((index, why))
        elif any(d != 0.0 for d in msg.D):
            self.lenses[msg.distortion_model] += 1


def lens_problem(model, D):
    """Why GeoFusion would drop frames with this distortion (ros/conversions.h's
    lensFromCameraInfo), or None."""
    if all(d == 0.0 for d in D):
        return None
    expected = {'plumb_bob': 5, 'rational_polynomial': 8}.get(model)
    if expected is None:
        return "distortion model '%s' is not supported" % model
    if len(D) != expected:
        return '%s with %d coefficients (it takes %d)' % (model, len(D), expected)
    if not all(math.isfinite(d) for d in D):
        return 'a distortion coefficient is not finite'
    return None


class DetectionStats(TopicStats):
    KINDS = ('non-finite pose', 'zero quaternion', 'non-unit quaternion',
             'score outside [0, 1]', 'empty class name')

    def __init__(self, topic):
        TopicStats.__init__(self, topic, ('geofusion/DetectionArray',))
        self.messages = []               # (header stamp, receive time, frame_id)
        self.detections = 0
        self.empty_messages = 0
        self.bad = collections.Counter()             # kind -> detections
        self.bad_examples = collections.defaultdict(list)
        self.bad_messages = 0
        self.bad_detections = 0
        self.definition_error = None

    def add_detections(self, msg, rec):
        stamp = msg.header.stamp.to_sec()
        index = self.add(stamp, rec, msg.header.frame_id)
        self.messages.append((stamp, rec, msg.header.frame_id))
        try:
            dets = msg.detections
            if not dets:
                self.empty_messages += 1
            message_bad = False
            for i, d in enumerate(dets):
                self.detections += 1
                kinds = detection_defects(d)
                for kind in kinds:
                    self.bad[kind] += 1
                    if len(self.bad_examples[kind]) < MAX_EXAMPLES:
                        self.bad_examples[kind].append('message %d detection %d (%s)' %
                                                       (index, i, d.class_name or '""'))
                if kinds:
                    self.bad_detections += 1
                    message_bad = True
            self.bad_messages += message_bad
        except AttributeError as e:
            self.definition_error = str(e)


class OdomStats(TopicStats):
    def __init__(self, topic):
        TopicStats.__init__(self, topic, ('nav_msgs/Odometry',))
        self.child_frames = collections.Counter()

    def add_odom(self, msg, rec):
        self.add(msg.header.stamp.to_sec(), rec, msg.header.frame_id)
        self.child_frames[msg.child_frame_id] += 1


class Edge:
    """One TF edge parent -> child as recorded on /tf (dynamic) or /tf_static."""

    def __init__(self):
        self.count = 0
        self.first = self.last = None    # smallest / largest stamp
        self.prev = None                 # previous stamp in receive order
        self.gaps = []                   # (a, b): consecutive stamps more than TF_GAP_S apart

    def add(self, stamp):
        self.count += 1
        self.first = stamp if self.first is None else min(self.first, stamp)
        self.last = stamp if self.last is None else max(self.last, stamp)
        if self.prev is not None and stamp - self.prev > TF_GAP_S:
            self.gaps.append((self.prev, stamp))
        self.prev = stamp


class TfStats:
    def __init__(self):
        self.topics = {TF_TOPIC: TopicStats(TF_TOPIC, TF_TYPES),
                       TF_STATIC_TOPIC: TopicStats(TF_STATIC_TOPIC, TF_TYPES)}
        self.dynamic = {}                # (parent, child) -> Edge
        self.static = {}
        self.per_child = {}              # child -> TopicStats of its /tf stamps (backwards check)
        self.slashed = collections.Counter()

    def add(self, topic, msg, rec):
        static = topic == TF_STATIC_TOPIC
        self.topics[topic].add(rec, rec)  # stamps are checked per transform below
        edges = self.static if static else self.dynamic
        for t in msg.transforms:
            for name in (t.header.frame_id, t.child_frame_id):
                if name.startswith('/'):
                    self.slashed[name] += 1
            parent, child = strip(t.header.frame_id), strip(t.child_frame_id)
            stamp = t.header.stamp.to_sec()
            edges.setdefault((parent, child), Edge()).add(stamp)
            if not static:
                stats = self.per_child.setdefault(
                    child, TopicStats("%s (frame '%s')" % (topic, child), ()))
                stats.add(stamp, rec)

    def frames(self):
        names = set()
        for parent, child in list(self.dynamic) + list(self.static):
            names.update((parent, child))
        return names

    def neighbours(self):
        adjacency = collections.defaultdict(set)
        for parent, child in list(self.dynamic) + list(self.static):
            adjacency[parent].add((child, (parent, child)))
            adjacency[child].add((parent, (parent, child)))
        return adjacency

    def path(self, start, goal):
        """Edges (parent, child) linking start to goal, ignoring direction; None if unlinked."""
        if start == goal:
            return []
        adjacency = self.neighbours()
        came_from = {start: None}
        queue = collections.deque([start])
        while queue:
            frame = queue.popleft()
            for other, edge in adjacency[frame]:
                if other in came_from:
                    continue
                came_from[other] = (frame, edge)
                if other == goal:
                    edges = []
                    while came_from[other] is not None:
                        other, edge = came_from[other]
                        edges.append(edge)
                    return edges[::-1]
                queue.append(other)
        return None

    def root(self, frame):
        parents = {c: p for p, c in list(self.dynamic) + list(self.static)}
        seen = set()
        while frame in parents and frame not in seen:
            seen.add(frame)
            frame = parents[frame]
        return frame


def strip(frame):
    return frame[1:] if frame.startswith('/') else frame


def image_defect(msg):
    """Why an image carries no usable pixels, or None."""
    if msg.width == 0 or msg.height == 0:
        return 'size %dx%d' % (msg.width, msg.height)
    if len(msg.data) != msg.step * msg.height:
        return '%d data bytes, step*height = %d*%d = %d' % (len(msg.data), msg.step, msg.height,
                                                           msg.step * msg.height)
    bpp = BYTES_PER_PIXEL.get(msg.encoding)
    if bpp and msg.step < bpp * msg.width:
        return 'step %d < %d bytes for a %d-pixel %s row' % (msg.step, bpp * msg.width, msg.width,
                                                              msg.encoding)
    return None


def detection_defects(d):
    """The reasons the estimator skips a detection (empty list: usable)."""
    kinds = []
    p, q = d.pose.position, d.pose.orientation
    values = (p.x, p.y, p.z, q.x, q.y, q.z, q.w)
    if not all(math.isfinite(v) for v in values):
        kinds.append('non-finite pose')
    else:
        norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
        if norm < 1e-9:
            kinds.append('zero quaternion')
        elif abs(norm - 1.0) > QUATERNION_TOLERANCE:
            kinds.append('non-unit quaternion')
    if not (math.isfinite(d.score) and 0.0 <= d.score <= 1.0):
        kinds.append('score outside [0, 1]')
    if not d.class_name:
        kinds.append('empty class name')
    return kinds


# ----------------------------------------------------------------------------------------------
# Reading

class Recording:
    def __init__(self, args):
        self.args = args
        self.rgb = ImageStats(args.rgb_topic)
        self.depth = ImageStats(args.depth_topic)
        self.info = CameraInfoStats(args.camera_info_topic)
        self.detections = DetectionStats(args.detections_topic)
        self.odom = OdomStats(args.odom_topic)
        self.tf = TfStats()
        self.by_topic = {
            args.rgb_topic: (self.rgb, self.rgb.add_image),
            args.depth_topic: (self.depth, self.depth.add_image),
            args.camera_info_topic: (self.info, self.info.add_info),
            args.detections_topic: (self.detections, self.detections.add_detections),
            args.odom_topic: (self.odom, self.odom.add_odom),
        }
        for topic in (TF_TOPIC, TF_STATIC_TOPIC):
            self.by_topic[topic] = (self.tf.topics[topic],
                                    lambda msg, rec, topic=topic: self.tf.add(topic, msg, rec))
        self.bag_topics = {}             # topic -> (type, count) from the bag's index
        self.bag_start = self.bag_end = None
        self.bag_messages = 0

    def read(self, path, progress):
        with rosbag.Bag(path, 'r') as bag:
            info = bag.get_type_and_topic_info()
            self.bag_topics = {t: (v.msg_type, v.message_count) for t, v in info.topics.items()}
            self.bag_messages = bag.get_message_count()
            if self.bag_messages:
                self.bag_start, self.bag_end = bag.get_start_time(), bag.get_end_time()
            wanted = [t for t in self.by_topic if t in self.bag_topics]
            total = sum(self.bag_topics[t][1] for t in wanted)
            for n, (topic, msg, t) in enumerate(bag.read_messages(topics=wanted)):
                stats, add = self.by_topic[topic]
                if stats.accepts(msg._type):
                    add(msg, t.to_sec())
                if progress and n % 500 == 0:
                    progress('validate_bag: %d / %d messages\r' % (n, total))
        if progress:
            progress(' ' * 60 + '\r')


# ----------------------------------------------------------------------------------------------
# Checks

def check_topics(report, rec):
    """Required topics present with the right types; odometry optional."""
    args = rec.args
    required = [(args.rgb_topic, rec.rgb), (args.depth_topic, rec.depth),
                (args.camera_info_topic, rec.info), (args.detections_topic, rec.detections)]
    for topic, stats in required + [(args.odom_topic, rec.odom)]:
        expected = stats.expected_types[0]
        if topic not in rec.bag_topics:
            candidates = sorted(t for t, (ty, _) in rec.bag_topics.items()
                                if ty in stats.expected_types and t not in rec.by_topic)
            hint = ('; topics of that type in the bag: %s (pass one with the topic option)' %
                    ', '.join(candidates)) if candidates else '; no other topic of that type'
            if topic == args.odom_topic:
                report.warning(topic, 'odometry topic (%s) not in the bag; odometry must then come '
                               'from TF alone%s' % (expected, hint))
            else:
                report.error(topic, 'required topic (%s) not in the bag%s' % (expected, hint))
            continue
        check_types(report, topic, stats)
    tf_topics = [t for t in (TF_TOPIC, TF_STATIC_TOPIC) if t in rec.bag_topics]
    if not tf_topics:
        report.error('/tf, /tf_static', 'neither /tf nor /tf_static is in the bag: the camera '
                     'cannot be placed in the odometry frame')
    for topic in tf_topics:
        check_types(report, topic, rec.tf.topics[topic])
    if TF_TOPIC in rec.bag_topics and TF_STATIC_TOPIC not in rec.bag_topics:
        report.ok(TF_STATIC_TOPIC, 'not in the bag (fine when /tf carries every transform)')


def check_types(report, topic, stats):
    wrong = {t: n for t, n in stats.types.items() if t not in stats.expected_types}
    if not wrong:
        return
    total = sum(stats.types.values())
    hint = ''
    if 'sensor_msgs/CompressedImage' in wrong:
        hint = ' (compressed: record the raw topic, or decompress with image_transport republish)'
    report.problem(sum(wrong.values()), total, topic, 'wrong message type: %s, expected %s%s' % (
        ', '.join('%s (%d messages)' % kv for kv in sorted(wrong.items())),
        ' or '.join(stats.expected_types), hint))


def check_stamps(report, stats, clock, what='messages'):
    """Zero stamps, stamps going backwards or repeating, stamps far from the receive time."""
    if stats.count == 0:
        return
    topic = stats.topic
    if stats.zero_stamps:
        report.problem(stats.zero_stamps, stats.count, topic, '%d of %d %s have a zero header '
                       'stamp (cannot be synchronised or placed in TF)' %
                       (stats.zero_stamps, stats.count, what))
    if stats.backwards:
        report.warning(topic, 'header stamps go backwards %s (a looping bag or a restarted '
                       'driver; the estimator restarts synchronisation and TF at each jump): %s' % (
                           plural(len(stats.backwards), 'time'),
                           examples('%s %d: %s after %s (%.3f s back)' % (
                               what.rstrip('s'), i, clock(s), clock(p), p - s)
                               for i, p, s, _ in stats.backwards)))
    if stats.repeated:
        report.warning(topic, '%d %s repeat the previous header stamp' % (stats.repeated, what))
    if stats.late:
        worst = ('stamped %.3f s ahead of its receive time' % -stats.max_delay
                 if stats.max_delay < 0 else 'received %.3f s after its stamp' % stats.max_delay)
        report.warning(topic, '%d of %d %s have a header stamp more than %.0f s from the time '
                       'they were recorded (worst: %s); clocks not synchronised, or stamps set '
                       'wrongly' % (stats.late, stats.count, what, MAX_RECEIVE_DELAY_S, worst))


def describe_counter(counter, fmt=str):
    return ', '.join('%s (%d)' % (fmt(k), n) for k, n in counter.most_common())


def size_text(size):
    return '%dx%d' % size


def check_rates(report, rec):
    for stats in (rec.rgb, rec.depth, rec.info, rec.detections, rec.odom,
                  rec.tf.topics[TF_TOPIC], rec.tf.topics[TF_STATIC_TOPIC]):
        if stats.count == 0:
            continue
        rate = stats.rate_hz()
        text = '%s, %s' % (plural(stats.count, 'message'), '%.1f Hz' % rate if rate else
                           'rate n/a')
        if isinstance(stats, ImageStats):
            text += ', %s, %s' % (describe_counter(stats.encodings),
                                  describe_counter(stats.sizes, size_text))
        if stats.frames:
            text += ', frame %s' % describe_counter(stats.frames, lambda f: "'%s'" % f)
        report.ok(stats.topic, text)


def check_images(report, rec):
    """Encodings, empty images, rgb vs depth size."""
    for stats, allowed, kind in ((rec.rgb, RGB_ENCODINGS, 'RGB'),
                                 (rec.depth, DEPTH_ENCODINGS, 'depth')):
        if stats.count == 0:
            continue
        bad = {e: n for e, n in stats.encodings.items() if e not in allowed}
        if bad:
            report.problem(sum(bad.values()), stats.count, stats.topic,
                           'unsupported %s encoding %s (%d of %d images); expected one of %s' % (
                               kind, ', '.join("'%s'" % e for e in sorted(bad)),
                               sum(bad.values()), stats.count, '/'.join(allowed)))
        if stats.empty:
            report.problem(len(stats.empty), stats.count, stats.topic,
                           '%d of %d images are empty or malformed: %s' % (
                               len(stats.empty), stats.count,
                               examples('image %d: %s' % e for e in stats.empty)))
        if stats.big_endian and kind == 'depth':
            report.warning(stats.topic, '%d big-endian depth images (is_bigendian=1); the '
                           'estimator reads them as little-endian' % stats.big_endian)
        if not bad and not stats.empty:
            report.ok(stats.topic, 'all %d images non-empty, with a supported encoding' %
                      stats.count)
    if rec.rgb.count and rec.depth.count and set(rec.rgb.sizes) != set(rec.depth.sizes):
        report.error(rec.depth.topic, 'depth image size %s differs from the RGB image size %s '
                     '(%s): depth must be registered to the RGB camera' % (
                         describe_counter(rec.depth.sizes, size_text),
                         describe_counter(rec.rgb.sizes, size_text), rec.rgb.topic))


def check_camera_info(report, rec):
    info = rec.info
    if info.count == 0:
        return
    if info.bad_focal:
        report.problem(len(info.bad_focal), info.count, info.topic,
                       '%d of %d camera_info messages have a zero or non-finite focal length: %s'
                       % (len(info.bad_focal), info.count,
                          examples('message %d: fx=%g fy=%g' % b for b in info.bad_focal)))
    if info.bad_lens:
        report.problem(len(info.bad_lens), info.count, info.topic,
                       '%d of %d camera_info messages have a lens the estimator cannot rectify '
                       '(their frames are dropped as unusable camera_info): %s'
                       % (len(info.bad_lens), info.count,
                          examples('message %d: %s' % b for b in info.bad_lens)))
    elif info.lenses:
        report.ok(info.topic, 'lens distortion %s: the images are rectified with it'
                  % describe_counter(info.lenses, str))
    image_sizes = set(rec.rgb.sizes or rec.depth.sizes)   # camera_info describes the RGB camera
    if image_sizes:
        bad = {s: n for s, n in info.sizes.items() if s not in image_sizes}
        if bad:
            report.problem(sum(bad.values()), info.count, info.topic,
                           'camera_info size %s differs from the image size %s (intrinsics for '
                           'another resolution)' % (describe_counter(info.sizes, size_text),
                                                    ', '.join(map(size_text, image_sizes))))
        elif not info.bad_focal:
            report.ok(info.topic, 'focal lengths set, size %s matches the images' %
                      describe_counter(info.sizes, size_text))


def check_sync(report, rec, clock):
    """Each detection message needs an RGB image and a depth image within --max-sync-spread."""
    det = rec.detections
    if det.count == 0 or rec.rgb.count == 0 or rec.depth.count == 0:
        return
    spread = rec.args.max_sync_spread
    rgb, depth = sorted(rec.rgb.stamps), sorted(rec.depth.stamps)
    rgb_s, depth_s = [s for s, _ in rgb], [s for s, _ in depth]
    rgb_by_rec = rec.rgb.stamps                      # receive order
    rgb_recs = [r for _, r in rgb_by_rec]
    info_s = sorted(rec.info.stamps)

    def window(stamps, items, s):
        return items[bisect.bisect_left(stamps, s - spread - 1e-9):
                     bisect.bisect_right(stamps, s + spread + 1e-9)]

    reasons = collections.Counter()
    unsynced_examples, offsets, later_by = [], [], []
    synced = no_info = 0
    for i, (s, r, _) in enumerate(det.messages):
        rgb_c, depth_c = window(rgb_s, rgb, s), window(depth_s, depth, s)
        rgb_ok = [x for x, xr in rgb_c if xr <= r + CAUSAL_TOLERANCE_S]
        depth_ok = [x for x, xr in depth_c if xr <= r + CAUSAL_TOLERANCE_S]
        if any(max(s, a, b) - min(s, a, b) <= spread + 1e-9 for a in rgb_ok for b in depth_ok):
            synced += 1
            if rec.info.count and not window(info_s, info_s, s):
                no_info += 1
            continue
        if not rgb_c:
            reason = 'no RGB image near the stamp'
        elif not depth_c:
            reason = 'no depth image near the stamp'
        elif not rgb_ok or not depth_ok:
            reason = 'only images recorded later'
            later_by.append(min(xr for _, xr in rgb_c + depth_c) - r)
        else:
            reason = 'RGB and depth too far apart'
        reasons[reason] += 1
        if len(unsynced_examples) < MAX_EXAMPLES:
            unsynced_examples.append('message %d at %s: %s' % (i, clock(s), reason))
        k = bisect.bisect_right(rgb_recs, r + 1e-6) - 1
        if k >= 0:
            offsets.append(s - rgb_by_rec[k][0])
    unsynced = det.count - synced
    if not unsynced:
        report.ok(det.topic, 'all %d detection messages have an RGB image and a depth image '
                  'within %.3f s' % (det.count, spread))
    else:
        why = []
        for reason, n in reasons.most_common():
            if reason == 'only images recorded later':
                reason += (', %.2f s or more after the detections (which cannot come from an '
                           'image not yet received)' % min(later_by))
            why.append('%s: %s' % (plural(n, 'message'), reason))
        if synced == 0:
            text = 'no detection message synchronises: none of the %d has' % det.count
        else:
            text = '%d of %d detection messages lack' % (unsynced, det.count)
        text += ' an RGB image and a depth image within %.3f s of %s stamp (%s)' % (
            spread, 'its' if synced == 0 else 'their', '; '.join(why))
        if len(offsets) >= 3:
            offsets.sort()
            median = offsets[len(offsets) // 2]
            if abs(median) > spread:
                text += ('; their stamps are typically %+.3f s from the latest RGB image recorded '
                         'before them, but must be exactly that image\'s stamp' % median)
        text += '; e.g. ' + examples(unsynced_examples)
        if synced == 0:
            report.error(det.topic, text)
        else:
            report.warning(det.topic, text)
    if no_info:
        report.problem(no_info, synced, rec.info.topic, '%d of %d synchronised detection messages '
                       'have no camera_info within %.3f s' % (no_info, synced, spread))


def check_detections(report, rec):
    det = rec.detections
    if det.count == 0:
        return
    if det.definition_error:
        report.error(det.topic, 'the geofusion/DetectionArray definition recorded in the bag does '
                     'not match this package (%s): recorded with an older message version?' %
                     det.definition_error)
        return
    if det.detections == 0:
        report.warning(det.topic, 'all %d detection messages are empty: nothing detected in the '
                       'whole recording' % det.count)
        return
    if det.bad_detections:
        kinds = ', '.join('%d %s' % (det.bad[k], k) for k in DetectionStats.KINDS if det.bad[k])
        ex = examples('%s: %s' % (k, e) for k in DetectionStats.KINDS
                      for e in det.bad_examples[k][:1])
        report.problem(det.bad_detections, det.detections, det.topic,
                       '%d of %d detections are malformed and will be skipped (%s), in %d of %d '
                       'messages: %s' % (det.bad_detections, det.detections, kinds,
                                         det.bad_messages, det.count, ex))
    else:
        report.ok(det.topic, '%d detections (%.1f a message, %d empty messages), all with a '
                  'finite pose, a unit quaternion, a score in [0, 1] and a class name' % (
                      det.detections, det.detections / det.count, det.empty_messages))


def check_frames(report, rec):
    """Detections and images must be in frames that TF links to the odometry frame."""
    args, tf = rec.args, rec.tf
    known = tf.frames()
    dynamic_edges = set()
    for name, n in tf.slashed.most_common():
        report.warning('/tf', "frame id '%s' starts with '/' in %s (tf2 strips it, but "
                       "lookups with it fail)" % (name, plural(n, 'transform')))
    children = collections.defaultdict(set)
    for parent, child in list(tf.dynamic) + list(tf.static):
        children[child].add(parent)
    for child, parents in sorted(children.items()):
        if len(parents) > 1:
            report.warning('/tf', "frame '%s' has %d parents (%s): two sources publish it" % (
                child, len(parents), ', '.join(sorted(parents))))
    if not known:
        if TF_TOPIC in rec.bag_topics or TF_STATIC_TOPIC in rec.bag_topics:
            report.error('/tf', 'no transforms in /tf or /tf_static')
        return dynamic_edges
    odom_known = args.odom_frame in known
    if not odom_known:
        report.error('/tf', "odometry frame '%s' is not in TF (frames: %s); set --odom-frame" % (
            args.odom_frame, ', '.join(sorted(known))))

    for stats, what in ((rec.detections, 'detections'), (rec.rgb, 'RGB images'),
                        (rec.depth, 'depth images')):
        for frame, n in sorted(stats.frames.items()):
            subject = stats.topic
            if frame == '':
                report.problem(n, stats.count, subject, '%d of %d %s have an empty '
                               'header.frame_id' % (n, stats.count, what))
                continue
            if frame.startswith('/'):
                report.warning(subject, "frame id '%s' starts with '/' (%d messages): tf2 "
                               "lookups reject it" % (frame, n))
            name = strip(frame)
            if name not in known:
                report.problem(n, stats.count, subject, "%s in an unknown frame '%s' (%d of %d "
                               "messages): no transform in /tf or /tf_static names it (TF "
                               "frames: %s)" % (what, frame, n, stats.count,
                                                ', '.join(sorted(known))))
                continue
            if not odom_known:
                continue
            path = tf.path(name, args.odom_frame)
            if path is None:
                report.problem(n, stats.count, subject, "%s in frame '%s' (%d of %d messages), "
                               "which TF does not link to '%s' (its tree's root is '%s', the "
                               "odometry frame's is '%s')" % (
                                   what, frame, n, stats.count, args.odom_frame, tf.root(name),
                                   tf.root(args.odom_frame)))
                continue
            dyn = [e for e in path if e in tf.dynamic and e not in tf.static]
            dynamic_edges.update(dyn)
            report.ok(subject, "%s in frame '%s' link to '%s' through TF: %s" % (
                what, frame, args.odom_frame, ' - '.join(chain(path, name)) or 'same frame'))

    rgb_frames = set(rec.rgb.frames)
    if rgb_frames and rec.detections.count:
        other = {f: n for f, n in rec.detections.frames.items() if f not in rgb_frames}
        if other:
            report.warning(rec.detections.topic, "detections framed in %s (%d of %d messages), "
                           "not in the RGB images' frame %s: detections must be expressed in the "
                           "RGB optical frame" % (
                               ', '.join("'%s'" % f for f in sorted(other)), sum(other.values()),
                               rec.detections.count,
                               ', '.join("'%s'" % f for f in sorted(rgb_frames))))

    if odom_known and args.base_frame in known:
        path = tf.path(args.base_frame, args.odom_frame)
        if path is None:
            report.warning('/tf', "base frame '%s' is not linked to '%s' in TF" % (
                args.base_frame, args.odom_frame))
        elif not dynamic_edges:
            dynamic_edges.update(e for e in path if e in tf.dynamic and e not in tf.static)
    elif odom_known:
        report.warning('/tf', "base frame '%s' is not in TF; set --base-frame" % args.base_frame)
    return dynamic_edges


def chain(path, start):
    """Frame names along a path of edges starting at frame start."""
    names, here = [start], start
    for parent, child in path:
        here = parent if here == child else child
        names.append(here)
    return names if path else []


def check_tf_coverage(report, rec, edges, clock):
    """Dynamic transforms on the camera's path to odom must cover the images' time span."""
    images = sorted(s for s, _ in (rec.rgb.stamps or rec.depth.stamps) if s > 0)
    topic = rec.rgb.topic if rec.rgb.stamps else rec.depth.topic
    if not images:
        return
    if not edges:
        return
    for parent, child in sorted(edges):
        edge = rec.tf.dynamic[(parent, child)]
        stretches = []                   # (from, to, images in it, where)
        before = bisect.bisect_left(images, edge.first - 1e-6)
        if before and edge.first - images[0] > TF_EDGE_TOLERANCE_S:
            stretches.append((images[0], edge.first, before, 'before the first transform'))
        after = len(images) - bisect.bisect_right(images, edge.last + 1e-6)
        if after and images[-1] - edge.last > TF_EDGE_TOLERANCE_S:
            stretches.append((edge.last, images[-1], after, 'after the last transform'))
        for a, b in edge.gaps:
            n = bisect.bisect_left(images, b - 1e-6) - bisect.bisect_right(images, a + 1e-6)
            if n:
                stretches.append((a, b, n, 'between two transforms'))
        name = "%s -> %s" % (parent, child)
        if not stretches:
            report.ok('/tf', '%s: %d transforms from %s to %s cover the images (%s to %s)' % (
                name, edge.count, clock(edge.first), clock(edge.last), clock(images[0]),
                clock(images[-1])))
            continue
        uncovered = sum(n for _, _, n, _ in stretches)
        text = '; '.join('%.2f s %s (from %s to %s) while %s keep coming' % (
            b - a, why, clock(a), clock(b), plural(n, 'image')) for a, b, n, why in stretches)
        report.problem(uncovered, len(images), '/tf', 'transform %s missing for %s: %s '
                       '(images on %s without a camera pose are skipped)' % (
                           name, plural(len(stretches), 'stretch', 'stretches'), text, topic))


def check_odometry(report, rec):
    odom, args = rec.odom, rec.args
    if odom.count == 0:
        return
    frames = {f: n for f, n in odom.frames.items() if strip(f) != args.odom_frame}
    if frames:
        report.warning(odom.topic, "odometry header.frame_id %s, not the odometry frame '%s' "
                       "(--odom-frame)" % (describe_counter(collections.Counter(frames),
                                                            lambda f: "'%s'" % f),
                                           args.odom_frame))
    children = {f: n for f, n in odom.child_frames.items() if strip(f) != args.base_frame}
    if children:
        report.warning(odom.topic, "odometry child_frame_id %s, not the base frame '%s' "
                       "(--base-frame)" % (describe_counter(collections.Counter(children),
                                                            lambda f: "'%s'" % f),
                                           args.base_frame))


def check_tf_stamps(report, rec, clock):
    for child in sorted(rec.tf.per_child):
        check_stamps(report, rec.tf.per_child[child], clock, 'transforms')


def validate(rec):
    report = Report(rec.args.quiet)
    clock = Clock()
    if rec.rgb.stamps:
        clock.ref = min(s for s, _ in rec.rgb.stamps)
    if rec.bag_messages:
        report.ok('bag', '%s: %d messages on %d topics, %.1f s recorded' % (
            rec.args.bag, rec.bag_messages, len(rec.bag_topics), rec.bag_end - rec.bag_start))
    else:
        report.error('bag', '%s holds no messages' % rec.args.bag)
    check_topics(report, rec)
    check_rates(report, rec)
    for stats in (rec.rgb, rec.depth, rec.info, rec.detections, rec.odom):
        check_stamps(report, stats, clock)
    check_tf_stamps(report, rec, clock)
    check_images(report, rec)
    check_camera_info(report, rec)
    check_detections(report, rec)
    check_sync(report, rec, clock)
    edges = check_frames(report, rec)
    check_tf_coverage(report, rec, edges, clock)
    check_odometry(report, rec)
    return report


# ----------------------------------------------------------------------------------------------

def robot_names(path=None):
    """The robot's topic and frame names: `path`, else the package's config/robots/fetch.yaml
    (beside the source, or found through ROS in an install space)."""
    if path is None:
        here = os.path.dirname(os.path.abspath(__file__))
        path = os.path.join(here, '..', '..', 'config', 'robots', 'fetch.yaml')
        if not os.path.exists(path):
            import roslib.packages
            path = os.path.join(roslib.packages.get_pkg_dir('geofusion'), 'config', 'robots',
                                'fetch.yaml')
    with open(path) as f:
        names = yaml.safe_load(f)
    if not isinstance(names, dict):
        raise ValueError('%s: not a mapping of names' % path)
    return names


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog='validate_bag.py',
        description='Checks a recording for GeoFusion before the estimator is run on it: topics, '
                    'message types, images, stamps, RGB-D-detection synchronisation, TF and '
                    'detection content. Exit code 0: no errors, 1: errors, 2: usage problem or '
                    'unreadable bag.')
    p.add_argument('bag', help='the .bag file')
    p.add_argument('--robot', metavar='FILE',
                   help='the robot\'s topic and frame names (default: the package\'s '
                        'config/robots/fetch.yaml); the options below override single names')
    p.add_argument('--rgb-topic')
    p.add_argument('--depth-topic')
    p.add_argument('--camera-info-topic')
    p.add_argument('--detections-topic')
    p.add_argument('--odom-topic')
    p.add_argument('--odom-frame')
    p.add_argument('--base-frame')
    p.add_argument('--max-sync-spread', type=float, default=0.05, metavar='SECONDS',
                   help='largest stamp spread of a synchronised RGB, depth and detections set '
                        '(default 0.05, as sync_max_interval_s)')
    p.add_argument('--quiet', action='store_true', help='print only errors, warnings and the '
                   'summary')
    args = p.parse_args(argv)
    try:
        robot = robot_names(args.robot)
    except (OSError, ValueError, KeyError, yaml.YAMLError) as e:
        p.error('cannot read the robot file: %s' % e)
    for name, key in (('rgb_topic', 'rgb_topic'), ('depth_topic', 'depth_topic'),
                      ('camera_info_topic', 'camera_info_topic'),
                      ('detections_topic', 'detections_topic'), ('odom_topic', 'wheel_odom_topic'),
                      ('odom_frame', 'odom_frame'), ('base_frame', 'base_frame')):
        if getattr(args, name) is None:
            setattr(args, name, robot[key])
    for name in ('rgb_topic', 'depth_topic', 'camera_info_topic', 'detections_topic',
                 'odom_topic'):
        topic = getattr(args, name)
        if not topic:
            p.error('--%s must not be empty' % name.replace('_', '-'))
        setattr(args, name, topic if topic.startswith('/') else '/' + topic)
    topics = [args.rgb_topic, args.depth_topic, args.camera_info_topic, args.detections_topic,
              args.odom_topic]
    if len(set(topics + [TF_TOPIC, TF_STATIC_TOPIC])) != len(topics) + 2:
        p.error('the topic options must name different topics (and not /tf or /tf_static)')
    if not (args.max_sync_spread >= 0.0 and math.isfinite(args.max_sync_spread)):
        p.error('--max-sync-spread must be a finite number >= 0')
    args.odom_frame, args.base_frame = strip(args.odom_frame), strip(args.base_frame)
    return args


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)

    def fail(text):
        sys.stderr.write('validate_bag.py: %s\n' % text)
        return EXIT_USAGE

    if not os.path.exists(args.bag):
        return fail('%s: no such file' % args.bag)
    if not os.path.isfile(args.bag):
        return fail('%s: not a file' % args.bag)
    progress = None
    if not args.quiet and sys.stderr.isatty():
        def progress(text):
            sys.stderr.write(text)
            sys.stderr.flush()
    rec = Recording(args)
    try:
        rec.read(args.bag, progress)
    except rosbag.ROSBagUnindexedException:
        return fail('%s is not indexed (an interrupted recording?); run `rosbag reindex %s` '
                    'first' % (args.bag, args.bag))
    except (rosbag.ROSBagException, genpy.MessageException, struct.error, EOFError) as e:
        return fail('cannot read %s: %s (not a ROS bag, or damaged)' % (args.bag, e))
    except OSError as e:
        return fail('cannot read %s: %s' % (args.bag, e.strerror or e))
    except KeyboardInterrupt:
        return fail('interrupted')
    report = validate(rec)
    report.print()
    if report.errors:
        verdict = 'fix the errors before running the estimator'
    elif report.warnings:
        verdict = 'usable, but read the warnings: they cost frames or detections'
    else:
        verdict = 'ready for the estimator'
    print('SUMMARY: %s, %s in %s: %s' % (plural(report.errors, 'error'),
                                         plural(report.warnings, 'warning'), args.bag, verdict))
    return EXIT_ERRORS if report.errors else EXIT_OK


if __name__ == '__main__':
    sys.exit(main())
