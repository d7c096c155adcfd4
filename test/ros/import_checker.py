#!/usr/bin/env python3
"""import_dataset on a user's folders (BOP, 7-Scenes, TUM RGB-D, made here) and on the shared real
frames (../shared/data/real, skipped with a message when absent):
- the recordings hold what the folders hold: images, depth in metres, intrinsics, camera poses on
  /tf as odom -> optical frame (hand-held: no /odom, no base), detections of a BOP results CSV or
  made from the ground truth with their along-ray bias; the ground truth names the platform;
- the real YCB-Video frames through import_dataset, run_offline and evaluate_run: every object
  mapped, none false; the real 7-Scenes frames through vo_benchmark: no frame lost;
- bad input: a folder that is no dataset, a malformed results row, bad arguments: exit codes and
  messages, nothing written."""
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

import numpy as np
import rosbag
import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from geofusion_test_utils import find_tool as tool  # noqa: E402

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
REAL = os.environ.get('GEOFUSION_REAL_DIR', os.path.join(SOURCE, '..', 'shared', 'data', 'real'))
FAILURES = []


def check(ok, what):
    print(('ok    ' if ok else 'FAIL  ') + what)
    if not ok:
        FAILURES.append(what)


def write_png(path, array):
    """A PNG of a uint16 (grey, 16 bit) or uint8 H x W x 3 (RGB) array, with zlib only."""
    if array.dtype == np.uint16:
        depth, colour = 16, 0
        rows = [b'\x00' + array[v].astype('>u2').tobytes() for v in range(array.shape[0])]
    else:
        depth, colour = 8, 2
        rows = [b'\x00' + array[v].astype(np.uint8).tobytes() for v in range(array.shape[0])]

    def chunk(kind, data):
        return (struct.pack('>I', len(data)) + kind + data +
                struct.pack('>I', zlib.crc32(kind + data) & 0xffffffff))
    header = struct.pack('>IIBBBBB', array.shape[1], array.shape[0], depth, colour, 0, 0, 0)
    with open(path, 'wb') as f:
        f.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', header) +
                chunk(b'IDAT', zlib.compress(b''.join(rows))) + chunk(b'IEND', b''))


def images(k, w=64, h=48):
    depth = np.full((h, w), 8000 + 100 * k, dtype=np.uint16)  # x 0.1 mm (BOP depth_scale 0.1)
    depth[0, :] = 0
    rgb = np.zeros((h, w, 3), dtype=np.uint8)
    rgb[:, :, 0] = 10 * k
    rgb[:, :, 1] = np.arange(w, dtype=np.uint8)[None, :]
    return depth, rgb


def rot_z(angle):
    c, s = math.cos(angle), math.sin(angle)
    return [c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0]


def make_bop(folder):
    """Three frames of a BOP scene '000007': two objects (primitive ids 8 and 21), camera poses."""
    os.makedirs(os.path.join(folder, 'rgb'))
    os.makedirs(os.path.join(folder, 'depth'))
    cameras, gt = {}, {}
    for k in range(1, 4):
        depth, rgb = images(k)
        write_png(os.path.join(folder, 'depth', '%06d.png' % k), depth)
        write_png(os.path.join(folder, 'rgb', '%06d.png' % k), rgb)
        cameras[str(k)] = {'cam_K': [60.0, 0, 32, 0, 60.0, 24, 0, 0, 1], 'depth_scale': 0.1,
                           'cam_R_w2c': rot_z(0.0), 'cam_t_w2c': [-10.0 * k, 0.0, 0.0]}
        gt[str(k)] = [{'obj_id': 8, 'cam_R_m2c': rot_z(0.1), 'cam_t_m2c': [10.0 * k, 0, 800]},
                      {'obj_id': 21, 'cam_R_m2c': rot_z(0.0), 'cam_t_m2c': [10.0 * k + 50, 0, 850]}]
    json.dump(cameras, open(os.path.join(folder, 'scene_camera.json'), 'w'))
    json.dump(gt, open(os.path.join(folder, 'scene_gt.json'), 'w'))


def bag_messages(path):
    out = {}
    with rosbag.Bag(path) as bag:
        for topic, msg, _ in bag.read_messages():
            out.setdefault(topic, []).append(msg)
    return out


def run(args, **kw):
    return subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, **kw)


def check_user_bop(tmp):
    folder = os.path.join(tmp, '000007')
    make_bop(folder)
    csv = os.path.join(tmp, 'results.csv')
    with open(csv, 'w') as f:
        f.write('scene_id,im_id,obj_id,score,R,t,time\n')
        f.write('7,1,8,0.8,%s,10 0 810,0.1\n' % ' '.join(str(x) for x in rot_z(0.1)))
        f.write('7,2,21,0.7,%s,70 0 850,0.1\n' % ' '.join(str(x) for x in rot_z(0.0)))
        f.write('7,2,99,0.7,%s,70 0 850,0.1\n' % ' '.join(str(x) for x in rot_z(0.0)))
        f.write('3,1,8,0.9,%s,0 0 500,0.1\n' % ' '.join(str(x) for x in rot_z(0.0)))
    out = os.path.join(tmp, 'out')
    r = run([tool('import_dataset'), '--in', folder, '--out-dir', out, '--model-set', 'primitives',
             '--detections', csv, '--quiet'])
    print(r.stdout)
    check(r.returncode == 0, 'a BOP folder with a results CSV is imported')
    if r.returncode != 0:
        return
    check('1 of unknown object ids skipped' in r.stdout, 'an unknown object id is counted')
    msgs = bag_messages(os.path.join(out, '000007.bag'))
    check(len(msgs.get('/head_camera/rgb/image_raw', [])) == 3, 'three colour images')
    check('/odom' not in msgs, 'hand-held: no wheel odometry')
    dets = msgs.get('/detections', [])
    check([len(d.detections) for d in dets] == [1, 1, 0], 'the CSV rows of scene 7 per frame')
    if dets and dets[0].detections:
        p = dets[0].detections[0].pose.position
        check(abs(p.x - 0.010) < 1e-9 and abs(p.z - 0.810) < 1e-9, 'detection poses in metres')
    depth = msgs['/head_camera/depth_registered/image_raw'][1]
    values = np.frombuffer(depth.data, dtype=np.uint16).reshape(depth.height, depth.width)
    check(depth.encoding == '16UC1' and values[5, 5] == 820 and values[0, 5] == 0,
          'depth converted to millimetres, holes kept (8200 x 0.1 mm = 820 mm)')
    info = msgs['/head_camera/rgb/camera_info'][0]
    check(abs(info.K[0] - 60.0) < 1e-9 and abs(info.K[2] - 32.0) < 1e-9, 'intrinsics from cam_K')
    frames = [t for m in msgs.get('/tf', []) for t in m.transforms]
    check(all(t.header.frame_id == 'odom' and t.child_frame_id == 'head_camera_rgb_optical_frame'
              for t in frames) and len(frames) == 3, '/tf: odom -> optical frame a frame')
    if len(frames) == 3:
        check(abs(frames[2].transform.translation.x - 0.030) < 1e-9,
              'camera pose from cam_R_w2c / cam_t_w2c (inverted)')
    gt = yaml.safe_load(open(os.path.join(out, '000007_gt.yaml')))
    check(gt['platform'] == 'hand_held' and gt['odometry'] == 'camera_trajectory',
          'the ground truth says hand-held, camera trajectory')
    check(len(gt['objects']) == 2, 'two objects in the ground truth')
    if gt['objects']:
        x = gt['objects'][0]['pose'][0]
        check(abs(x - 0.020) < 1e-9, 'object world pose = camera pose x object in camera')
    check(len(gt['frames']) == 3 and all(f['keyframe'] for f in gt['frames']), 'frames listed')
    check(all(len(f['visible_fraction']) == 2 for f in gt['frames']), 'visibility per object')

    # Detections from the ground truth with an along-ray bias.
    out2 = os.path.join(tmp, 'out2')
    r = run([tool('import_dataset'), '--in', folder, '--out-dir', out2, '--model-set',
             'primitives', '--detections', 'truth', '--ray-bias', '0.02,0.04', '--quiet'])
    check(r.returncode == 0, 'a BOP folder with detections from the ground truth')
    if r.returncode == 0:
        dets = bag_messages(os.path.join(out2, '000007.bag'))['/detections']
        errors = []
        for k, d in enumerate(dets):
            for det in d.detections:
                true_t = np.array([10.0 * (k + 1) + (50 if det.class_name == '061_foam_brick'
                                                      else 0), 0, 850 if det.class_name ==
                                   '061_foam_brick' else 800]) / 1000.0
                p = det.pose.position
                errors.append(np.dot(np.array([p.x, p.y, p.z]) - true_t,
                                     true_t / np.linalg.norm(true_t)))
        check(len(errors) == 6 and all(0.02 - 1e-9 <= abs(e) <= 0.04 + 1e-9 for e in errors),
              'every detection 2-4 cm off along its ray: %s' % np.round(errors, 4).tolist())


def check_user_7scenes_and_tum(tmp):
    seven = os.path.join(tmp, 'seven')
    os.makedirs(seven)
    for k in range(3):
        depth, rgb = images(k)
        depth[1, :] = 65535
        write_png(os.path.join(seven, 'frame-%06d.depth.png' % k), depth)
        write_png(os.path.join(seven, 'frame-%06d.color.png' % k), rgb)
        pose = np.eye(4)
        pose[0, 3] = 0.1 * k
        np.savetxt(os.path.join(seven, 'frame-%06d.pose.txt' % k), pose)
    out = os.path.join(tmp, 'seven_out')
    r = run([tool('import_dataset'), '--in', seven, '--out-dir', out, '--model-set', 'primitives',
             '--detections', 'none', '--quiet'])
    check(r.returncode == 0, 'a 7-Scenes folder is imported')
    if r.returncode == 0:
        msgs = bag_messages(os.path.join(out, 'seven.bag'))
        check('/detections' not in msgs, 'no detections asked for, none written')
        d = msgs['/head_camera/depth_registered/image_raw'][0]
        v = np.frombuffer(d.data, dtype=np.uint16).reshape(d.height, d.width)
        check(v[1, 3] == 0 and v[5, 5] == 8000, '7-Scenes 65535 is no reading; millimetres kept')
        stamps = [m.header.stamp.to_sec() for m in msgs['/head_camera/rgb/image_raw']]
        check(abs(stamps[1] - stamps[0] - 1 / 30.0) < 1e-6, 'frames at 30 Hz')
    tum = os.path.join(tmp, 'rgbd_dataset_freiburg1_test')
    os.makedirs(os.path.join(tum, 'rgb'))
    os.makedirs(os.path.join(tum, 'depth'))
    with open(os.path.join(tum, 'rgb.txt'), 'w') as rt, \
            open(os.path.join(tum, 'depth.txt'), 'w') as dt, \
            open(os.path.join(tum, 'groundtruth.txt'), 'w') as gt:
        rt.write('# color images\n')
        for k in range(3):
            t = 1305031102.0 + k / 30.0
            depth, rgb = images(k)
            write_png(os.path.join(tum, 'rgb', '%.6f.png' % t), rgb)
            write_png(os.path.join(tum, 'depth', '%.6f.png' % (t + 0.005)), depth)
            rt.write('%.6f rgb/%.6f.png\n' % (t, t))
            dt.write('%.6f depth/%.6f.png\n' % (t + 0.005, t + 0.005))
        for k in range(12):
            t = 1305031102.0 - 0.01 + k * 0.01
            gt.write('%.4f %.4f 0 0 0 0 0 1\n' % (t, t - 1305031102.0))
    out = os.path.join(tmp, 'tum_out')
    r = run([tool('import_dataset'), '--in', tum, '--out-dir', out, '--model-set', 'primitives',
             '--detections', 'none', '--quiet'])
    check(r.returncode == 0, 'a TUM RGB-D folder is imported')
    if r.returncode == 0:
        msgs = bag_messages(os.path.join(out, 'rgbd_dataset_freiburg1_test.bag'))
        info = msgs['/head_camera/rgb/camera_info'][0]
        check(abs(info.K[0] - 517.3) < 1e-9, 'freiburg1 intrinsics')
        d = msgs['/head_camera/depth_registered/image_raw'][0]
        v = np.frombuffer(d.data, dtype=np.uint16).reshape(d.height, d.width)
        check(v[5, 5] == 1600, 'TUM depth 5000 units a metre (8000 -> 1600 mm)')
        tf = [t for m in msgs['/tf'] for t in m.transforms]
        check(len(tf) == 3 and abs(tf[1].transform.translation.x - 1 / 30.0) < 1e-4,
              'camera pose interpolated at the image stamp')


def check_meta_converter(tmp, ycb):
    """ycbv_meta_to_bop on the real meta.mat files gives the folder's BOP files."""
    out = os.path.join(tmp, 'meta')
    r = run([sys.executable, os.path.join(SOURCE, 'src', 'tools', 'ycbv_meta_to_bop.py'), ycb,
             '--out-dir', out])
    print(r.stdout)
    check(r.returncode == 0, 'ycbv_meta_to_bop reads the YCB-Video meta.mat files')
    if r.returncode != 0:
        return
    for name in ('scene_camera.json', 'scene_gt.json'):
        mine, theirs = json.load(open(os.path.join(out, name))), json.load(open(os.path.join(ycb, name)))
        same = sorted(mine) == sorted(theirs)
        for k in theirs:
            a, b = mine.get(k), theirs[k]
            if name == 'scene_gt.json':
                same = same and len(a) == len(b) and all(
                    x['obj_id'] == y['obj_id'] and np.allclose(x['cam_R_m2c'], y['cam_R_m2c'], atol=1e-6)
                    and np.allclose(x['cam_t_m2c'], y['cam_t_m2c'], atol=1e-3) for x, y in zip(a, b))
            else:
                same = same and np.allclose(a['cam_K'], b['cam_K']) and \
                    abs(a['depth_scale'] - b['depth_scale']) < 1e-9 and np.allclose(
                        a['ycbv_rotation_translation_matrix_3x4'],
                        b['ycbv_rotation_translation_matrix_3x4'], atol=1e-6)
        check(same, 'meta.mat -> %s equals the folder\'s' % name)


def check_real(tmp):
    ycb = os.path.join(REAL, 'ycbv_video', '0000')
    if not os.path.exists(os.path.join(ycb, 'scene_camera.json')):
        print('SKIP  real YCB-Video frames not found at %s' % ycb)
    else:
        check_meta_converter(tmp, ycb)
        out = os.path.join(tmp, 'real')
        r = run([tool('import_dataset'), '--in', ycb, '--out-dir', out, '--name', 'ycbv_0000',
                 '--ray-bias', '0.02,0.04', '--quiet'])
        print(r.stdout)
        check(r.returncode == 0, 'the real YCB-Video frames are imported')
        bag = os.path.join(out, 'ycbv_0000.bag')
        gt = os.path.join(out, 'ycbv_0000_gt.yaml')
        results = os.path.join(out, 'results.yaml')
        r = run([tool('run_offline'), '--bag', bag, '--out', results, '--model-set', 'ycb_video',
                 '--keyframe-every', '1', '--quiet'])
        print(r.stdout[-2000:])
        check(r.returncode == 0, 'run_offline on the imported recording')
        ev = os.path.join(out, 'evaluation.json')
        r = run([tool('evaluate_run'), '--results', results, '--ground-truth', gt, '--json', ev,
                 '--model-set', 'ycb_video'])
        print(r.stdout[-2000:])
        check(r.returncode == 0, 'evaluate_run against the imported ground truth')
        if r.returncode == 0:
            e = json.load(open(ev))
            final = e['final_map']
            check(final['true_objects'] == 3 and final['matched'] == 3 and final['objects'] == 3,
                  'every object of the real frames mapped, none false: %s' % final)
    seven = os.path.join(REAL, '7scenes_redkitchen')
    if not os.path.exists(os.path.join(seven, 'frame-000000.depth.png')):
        print('SKIP  real 7-Scenes frames not found at %s' % seven)
        return
    out = os.path.join(tmp, 'seven_real')
    r = run([tool('import_dataset'), '--in', seven, '--out-dir', out, '--name', 'redkitchen',
             '--model-set', 'primitives', '--detections', 'none', '--quiet'])
    check(r.returncode == 0, 'the real 7-Scenes frames are imported')
    r = run([tool('vo_benchmark'), '--bag', os.path.join(out, 'redkitchen.bag'),
             '--ground-truth', os.path.join(out, 'redkitchen_gt.yaml'), '--out-dir', out])
    print(r.stdout[-1500:])
    check(r.returncode == 0, 'vo_benchmark on the imported 7-Scenes recording')
    if r.returncode == 0:
        j = json.load(open(os.path.join(out, 'redkitchen_vo.json')))
        check(j['lost_frames'] == 0 and j['ate_rmse_m'] < 0.032,
              'visual odometry: no frame lost, ATE %.2f cm' % (100 * j['ate_rmse_m']))


def check_bad_input(tmp):
    empty = os.path.join(tmp, 'empty')
    os.makedirs(empty)
    r = run([tool('import_dataset'), '--in', empty, '--out-dir', os.path.join(tmp, 'x')])
    check(r.returncode == 1 and 'not a dataset folder' in r.stdout, 'no dataset: exit 1, said')
    check(not os.path.exists(os.path.join(tmp, 'x', 'empty.bag')), '... nothing written')
    folder = os.path.join(tmp, '000007')
    bad = os.path.join(tmp, 'bad.csv')
    with open(bad, 'w') as f:
        f.write('scene_id,im_id,obj_id,score,R,t,time\n7,1,8,0.8,1 0 0 0 1 0,0 0 1,0.1\n')
    r = run([tool('import_dataset'), '--in', folder, '--out-dir', os.path.join(tmp, 'y'),
             '--model-set', 'primitives', '--detections', bad])
    check(r.returncode == 1 and 'line 2' in r.stdout, 'a malformed results row: exit 1, its line')
    r = run([tool('import_dataset'), '--in', folder, '--out-dir', tmp, '--ray-bias', '0.04,0.02'])
    check(r.returncode == 2 and '--ray-bias' in r.stdout, 'bad arguments: exit 2, the flag named')


def main():
    tmp = tempfile.mkdtemp(prefix='geofusion_import_')
    try:
        check_user_bop(tmp)
        check_user_7scenes_and_tum(tmp)
        check_bad_input(tmp)
        check_real(tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print('%d failure(s)' % len(FAILURES))
    return 1 if FAILURES else 0


if __name__ == '__main__':
    sys.exit(main())
