"""Recordings whose detections are vision_msgs/Detection3DArray (the ROS Noetic layout), written
without the vision_msgs package: the message classes are generated from the definition text in
test/ros/vision_msgs_noetic (the .msg files of ros-perception/vision_msgs, noetic-devel,
Apache-2.0), as rosbag itself does when it reads a bag. Imported by the checkers, not run."""
import os

VISION_TOPIC = '/vision_detections'
NATIVE_TOPIC = '/detections'
MSG_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'vision_msgs_noetic')


def message_classes(id_type='int64'):
    """{'Detection3DArray': class, ...} generated from the definition text. id_type 'string'
    makes the short-lived variant whose class id was a string (another MD5 sum)."""
    import genmsg
    import genmsg.msg_loader as loader
    import genpy.dynamic
    import rospkg
    rospack = rospkg.RosPack()
    msg_dir = MSG_DIR
    if id_type != 'int64':
        import tempfile
        msg_dir = tempfile.mkdtemp(prefix='vision_msgs_variant_')
        for name in os.listdir(MSG_DIR):
            with open(os.path.join(MSG_DIR, name)) as f:
                text = f.read()
            if name == 'ObjectHypothesisWithPose.msg':
                text = text.replace('int64 id', '%s id' % id_type)
            with open(os.path.join(msg_dir, name), 'w') as f:
                f.write(text)
    search = {'vision_msgs': [msg_dir]}
    for pkg in ('std_msgs', 'geometry_msgs', 'sensor_msgs'):
        search[pkg] = [os.path.join(rospack.get_path(pkg), 'msg')]
    context = genmsg.MsgContext.create_default()
    spec = loader.load_msg_by_type(context, 'vision_msgs/Detection3DArray', search)
    loader.load_depends(context, spec, search)
    full_text = genmsg.compute_full_text(context, spec)
    classes = genpy.dynamic.generate_dynamic('vision_msgs/Detection3DArray', full_text)
    return {t.split('/')[-1]: c for t, c in classes.items() if t.startswith('vision_msgs/')}


def to_vision_bag(src_path, out_path, class_id=lambda d: d.class_id, decoys=True,
                  id_type='int64'):
    """Copies a recording with its DetectionArray messages on /detections written as
    Detection3DArray on /vision_detections: one result per detection with class id
    class_id(detection), its score and pose; with `decoys`, each detection also carries a
    lower-scoring hypothesis of a class id no model set maps (-7), which the converter must pass
    over. Returns the number of detections written."""
    import rosbag
    classes = message_classes(id_type)
    written = 0
    with rosbag.Bag(src_path) as src, rosbag.Bag(out_path, 'w') as dst:
        for topic, msg, t in src.read_messages():
            if topic != NATIVE_TOPIC:
                dst.write(topic, msg, t)
                continue
            out = classes['Detection3DArray']()
            out.header = msg.header
            for d in msg.detections:
                det = classes['Detection3D']()
                det.header = msg.header
                h = classes['ObjectHypothesisWithPose']()
                h.id = class_id(d) if id_type == 'int64' else str(class_id(d))
                h.score = d.score
                h.pose.pose = d.pose
                det.results.append(h)
                if decoys:
                    decoy = classes['ObjectHypothesisWithPose']()
                    decoy.id = -7 if id_type == 'int64' else '-7'
                    decoy.score = d.score * 0.5
                    decoy.pose.pose = d.pose
                    det.results.append(decoy)
                det.bbox.center.orientation.w = 1.0
                out.detections.append(det)
                written += 1
            dst.write(VISION_TOPIC, out, t)
    return written
