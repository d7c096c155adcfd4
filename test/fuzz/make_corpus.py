#!/usr/bin/python3
"""Writes the fuzzers' seed corpus, test/fuzz/corpus/<target>/: a few small valid inputs each.
Run with a built workspace's devel/setup.bash sourced (the generated geofusion messages):

    /usr/bin/python3 test/fuzz/make_corpus.py [OUT_DIR]   (default: corpus/ beside this script)

The parameter seeds are copies of the repository's own files (config/, test/ros/config/); the
rest is made here, deterministically."""
import io
import os
import shutil
import struct
import sys

import rosbag
import rospy
from geometry_msgs.msg import Pose, TransformStamped
from sensor_msgs.msg import CameraInfo, Image, RegionOfInterest
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage

from geofusion.msg import Detection, DetectionArray

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
FRAME = 'head_camera_rgb_optical_frame'


def write(out, target, name, data):
    os.makedirs(os.path.join(out, target), exist_ok=True)
    with open(os.path.join(out, target, name), 'wb') as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def serialised(msg):
    buf = io.BytesIO()
    msg.serialize(buf)
    return buf.getvalue()


def detection(name, class_id, score, xyz, q=(0.0, 0.0, 0.0, 1.0), box=(10, 20, 30, 40)):
    d = Detection(class_name=name, class_id=class_id, score=score)
    d.pose.position.x, d.pose.position.y, d.pose.position.z = xyz
    d.pose.orientation.x, d.pose.orientation.y, d.pose.orientation.z, d.pose.orientation.w = q
    d.box = RegionOfInterest(x_offset=box[0], y_offset=box[1], width=box[2], height=box[3])
    return d


def detections(stamp, dets):
    return DetectionArray(header=Header(seq=1, stamp=stamp, frame_id=FRAME), detections=dets)


def short_definition(text):
    lines = (line.split('#')[0].rstrip() for line in text.splitlines())
    return '\n'.join(line for line in lines if line) + '\n'


def vision_header(frame, seq=1, secs=100, nsecs=500000000):
    return struct.pack('<III', seq, secs, nsecs) + struct.pack('<I', len(frame)) + frame.encode()


def vision_array(frame, dets):
    """The serialised bytes of a Noetic vision_msgs/Detection3DArray (vision_msgs is not a
    dependency): `dets` per detection a list of (class id, score, xyz, quaternion xyzw)."""
    out = vision_header(frame) + struct.pack('<I', len(dets))
    for hyps in dets:
        out += vision_header(frame) + struct.pack('<I', len(hyps))
        for class_id, score, xyz, q in hyps:
            out += struct.pack('<qd', class_id, score) + struct.pack('<7d', *xyz, *q)
            out += struct.pack('<36d', *([0.0] * 36))
        out += struct.pack('<7d', 0, 0, 0, 0, 0, 0, 1) + struct.pack('<3d', 0, 0, 0)  # bbox
        out += vision_header('', 0, 0, 0) + struct.pack('<III', 0, 0, 0) + b'\x00'  # cloud
        out += struct.pack('<III', 0, 0, 0) + b'\x01'
    return out


VISION_MD5 = '05c51d9aea1fb4cfdc8effb94f197b6f'


class VisionType:
    """What rosbag's raw write needs of a message class."""
    _type = 'vision_msgs/Detection3DArray'
    _md5sum = VISION_MD5
    _full_text = 'see vision_msgs (Noetic)'


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, 'corpus')
    t = rospy.Time(100, 500000000)
    three = [detection('003_cracker_box', 2, 0.9, (0.1, -0.05, 0.8), (0.0, 0.0, 0.7071068, 0.7071068)),
             detection('005_tomato_soup_can', 4, 0.6, (-0.2, 0.1, 1.2)),
             detection('unknown_thing', -1, 0.7, (0.0, 0.0, 0.5), box=(0, 0, 0, 0))]
    faulty = [detection('004_sugar_box', 3, 0.8, (0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 0.0)),
              detection('004_sugar_box', 3, 1.5, (0.0, 0.0, 1.0)),
              detection('', 3, 0.5, (0.0, 0.0, 1.0)),
              detection('061_foam_brick', 21, 0.5, (0.0, 0.0, 25.0)),
              detection('061_foam_brick', 21, 0.5, (float('nan'), 0.0, 1.0))]
    write(out, 'detections', 'empty', serialised(detections(t, [])))
    write(out, 'detections', 'three', serialised(detections(t, three)))
    write(out, 'detections', 'faulty', serialised(detections(t, faulty)))
    unit = (0.0, 0.0, 0.0, 1.0)
    write(out, 'vision_detections', 'empty', vision_array(FRAME, []))
    write(out, 'vision_detections', 'three', vision_array(FRAME, [
        [(2, 0.9, (0.1, -0.05, 0.8), (0.0, 0.0, 0.7071068, 0.7071068)), (9, 0.3, (0.1, 0, 0.8), unit)],
        [(4, 0.6, (-0.2, 0.1, 1.2), unit)],
        [(999, 0.7, (0.0, 0.0, 0.5), unit)]]))
    write(out, 'vision_detections', 'faulty', vision_array('', [
        [], [(3, 0.8, (0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 0.0))],
        [(3, float('nan'), (0.0, 0.0, 1.0), unit)], [(21, 0.5, (float('inf'), 0.0, 1.0), unit)]]))

    write(out, 'model_set', 'primitives.yaml', """name: seeds
classes:
  - name: my_box
    id: 30
    box: [0.1, 0.05, 0.03]
    symmetry: {type: discrete, rotations: [{axis: [0, 0, 1], angle_deg: 180}]}
  - name: my_can
    id: 31
    cylinder: {radius: 0.03, height: 0.1}
    symmetry: {type: continuous, axis: [0, 0, 1]}
""")
    write(out, 'model_set', 'mesh.yaml', """name: with_files
classes:
  - name: tetra
    id: 1
    mesh: box.obj
    points: box.xyz
    symmetry: none
  - name: missing
    id: 2
    mesh: no_such_file.obj
""")
    write(out, 'model_set', 'features.yaml', """name: features
classes:
  - name: slab
    id: 5
    box: [0.2, 0.2, 0.02]
    features:
      planes: [{center: [0, 0, 0.01], normal: [0, 0, 1], boundary: [[0.1, 0.1, 0.01], [-0.1, 0.1, 0.01], [-0.1, -0.1, 0.01]]}]
      curves: [{end_a: [0, 0, -0.01], end_b: [0, 0, 0.01], radius: 0.1}]
""")

    for src in ('config/scene_estimator.yaml', 'config/visual_odometry.yaml',
                'config/detection_viewer.yaml', 'test/ros/config/estimator_settings.yaml',
                'test/ros/config/out_of_range.yaml'):
        os.makedirs(os.path.join(out, 'config'), exist_ok=True)
        shutil.copy(os.path.join(ROOT, src), os.path.join(out, 'config', os.path.basename(src)))

    # Mesh seeds: the first byte picks the type (0 OBJ, 1 PLY, 2 STL, 3 OFF).
    write(out, 'mesh', 'tetra.obj', b'\x00' + b"""# a tetrahedron with texture coordinates
v 0 0 0
v 0.1 0 0
v 0 0.1 0
v 0 0 0.1
vt 0 0
vt 1 0
vt 0 1
vt 1 1
f 1/1 3/3 2/2
f 1/1 2/2 4/4
f 1/1 4/4 3/3
f 2/2 3/3 4/4
""")
    write(out, 'mesh', 'tetra.ply', b'\x01' + b"""ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
element face 4
property list uchar int vertex_indices
end_header
0 0 0
0.1 0 0
0 0.1 0
0 0 0.1
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
""")
    facets = [((0, 0, 0), (0, 0.1, 0), (0.1, 0, 0)), ((0, 0, 0), (0.1, 0, 0), (0, 0, 0.1)),
              ((0, 0, 0), (0, 0, 0.1), (0, 0.1, 0)), ((0.1, 0, 0), (0, 0.1, 0), (0, 0, 0.1))]
    stl = 'solid tetra\n'
    for f in facets:
        stl += ' facet normal 0 0 0\n  outer loop\n'
        stl += ''.join('   vertex %g %g %g\n' % v for v in f)
        stl += '  endloop\n endfacet\n'
    write(out, 'mesh', 'tetra.stl', b'\x02' + (stl + 'endsolid tetra\n').encode())
    write(out, 'mesh', 'tetra.off', b'\x03' + b"""OFF
4 4 6
0 0 0
0.1 0 0
0 0.1 0
0 0 0.1
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
""")

    # Bag seeds: one frame of the estimator's inputs (a 4x3 depth image) with TF, uncompressed and bz2;
    # the connections' message definitions without their comments, to keep the files small.
    for name, compression in (('frames.bag', 'none'), ('frames_bz2.bag', 'bz2')):
        path = os.path.join(out, 'bag', name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with rosbag.Bag(path, 'w', compression=compression) as bag:
            for i in range(1):
                stamp = rospy.Time(100 + i, 0)
                header = Header(seq=i, stamp=stamp, frame_id=FRAME)
                depth = Image(header=header, height=3, width=4, encoding='32FC1', is_bigendian=0,
                              step=16, data=bytes(48))
                info = CameraInfo(header=header, height=3, width=4, distortion_model='plumb_bob',
                                  D=[0.0] * 5, K=[2.0, 0, 2.0, 0, 2.0, 1.5, 0, 0, 1],
                                  R=[1.0, 0, 0, 0, 1, 0, 0, 0, 1],
                                  P=[2.0, 0, 2.0, 0, 0, 2.0, 1.5, 0, 0, 0, 1, 0])
                tf = TFMessage(transforms=[TransformStamped(
                    header=Header(stamp=stamp, frame_id='odom'), child_frame_id=FRAME)])
                tf.transforms[0].transform.rotation.w = 1.0
                for topic, msg in (('/tf', tf), ('/head_camera/depth_registered/image_raw', depth),
                                   ('/head_camera/rgb/camera_info', info),
                                   ('/detections', detections(stamp, three[:2]))):
                    bag.write(topic, msg, stamp, connection_header={
                        'topic': topic, 'type': msg._type, 'md5sum': msg._md5sum,
                        'message_definition': short_definition(msg._full_text)})
    # A bag with a vision_msgs/Detection3DArray (written raw: vision_msgs is not a dependency).
    path = os.path.join(out, 'bag', 'vision.bag')
    with rosbag.Bag(path, 'w') as bag:
        data = vision_array(FRAME, [[(2, 0.9, (0.1, -0.05, 0.8), unit)], [(999, 0.5, (0, 0, 1), unit)]])
        bag.write('/detections_3d', ('vision_msgs/Detection3DArray', data, VISION_MD5, None, VisionType),
                  rospy.Time(100, 0), raw=True, connection_header={
                      'topic': '/detections_3d', 'type': 'vision_msgs/Detection3DArray',
                      'md5sum': VISION_MD5, 'message_definition': 'see vision_msgs (Noetic)'})
    for target in sorted(os.listdir(out)):
        files = sorted(os.listdir(os.path.join(out, target)))
        print('%s: %s' % (target, ', '.join('%s (%d B)' % (f, os.path.getsize(
            os.path.join(out, target, f))) for f in files)))


if __name__ == '__main__':
    main()
