#!/usr/bin/env python3
"""The visual odometry on real frames beside Open3D's and OpenCV's RGB-D odometry (make bench-real,
docs/BENCHMARK.md "Real frames"): the 7-Scenes frames of ../shared/data/real, every method frame
to frame on one thread, ATE RMSE after a rigid alignment (Umeyama, no scale: as vo_benchmark) and
the median time a frame (the odometry alone, images already decoded).

    vo_real.py --frames DIR --ours OURS_VO.json --out DIR

OURS_VO.json is vo_benchmark's file for the same frames (imported with import_dataset). Needs the
Python packages open3d and opencv-contrib-python (scripts/bench_real.sh installs them in their own
environment). Exit 0 with the table written, 1 when the frames or a package are missing."""
import argparse
import glob
import json
import os
import sys
import time

os.environ.setdefault('OMP_NUM_THREADS', '1')

import numpy as np  # noqa: E402


def umeyama_ate(est, truth):
    """RMSE of positions after the rigid alignment (rotation and translation, no scale)."""
    est, truth = np.asarray(est), np.asarray(truth)
    mu_e, mu_t = est.mean(0), truth.mean(0)
    cov = (truth - mu_t).T @ (est - mu_e) / len(est)
    U, _, Vt = np.linalg.svd(cov)
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:
        S[2, 2] = -1
    R = U @ S @ Vt
    aligned = (R @ (est - mu_e).T).T + mu_t
    return float(np.sqrt(np.mean(np.sum((aligned - truth) ** 2, axis=1))))


def load_frames(folder):
    import cv2
    K = np.loadtxt(os.path.join(folder, 'camera-intrinsics.txt'))
    frames = []
    for depth_path in sorted(glob.glob(os.path.join(folder, 'frame-*.depth.png'))):
        stem = depth_path[:-len('.depth.png')]
        colour = cv2.imread(stem + '.color.jpg') if os.path.exists(stem + '.color.jpg') else \
            cv2.imread(stem + '.color.png')
        depth = cv2.imread(depth_path, cv2.IMREAD_ANYDEPTH).astype(np.uint16)
        depth[depth == 65535] = 0
        frames.append({'bgr': colour, 'depth_mm': depth, 'pose': np.loadtxt(stem + '.pose.txt')})
    return K, frames


def chain(relative):
    """Camera poses from frame-to-frame transforms T_prev_cur (None: lost, pose held)."""
    poses = [np.eye(4)]
    for T in relative:
        poses.append(poses[-1] @ (T if T is not None else np.eye(4)))
    return poses


def run_open3d(K, frames):
    import open3d as o3d
    h, w = frames[0]['depth_mm'].shape
    intr = o3d.camera.PinholeCameraIntrinsic(w, h, K[0, 0], K[1, 1], K[0, 2], K[1, 2])
    option = o3d.pipelines.odometry.OdometryOption()
    jac = o3d.pipelines.odometry.RGBDOdometryJacobianFromHybridTerm()
    images = [o3d.geometry.RGBDImage.create_from_color_and_depth(
        o3d.geometry.Image(np.ascontiguousarray(f['bgr'][:, :, ::-1])),
        o3d.geometry.Image(f['depth_mm']), depth_scale=1000.0, depth_trunc=4.0,
        convert_rgb_to_intensity=True) for f in frames]
    relative, times, lost = [], [], 0
    for a, b in zip(images[:-1], images[1:]):
        t0 = time.perf_counter()
        ok, T_b_a, _ = o3d.pipelines.odometry.compute_rgbd_odometry(b, a, intr, np.eye(4), jac,
                                                                    option)
        times.append(1000.0 * (time.perf_counter() - t0))
        relative.append(T_b_a if ok else None)  # maps frame b's points into frame a
        lost += not ok
    return chain(relative), times, lost


def run_opencv(K, frames, kind):
    import cv2
    cv2.setNumThreads(1)
    settings = cv2.OdometrySettings()
    settings.setCameraMatrix(K.astype(np.float32))
    types = {'rgb': cv2.OdometryType_RGB, 'rgb_depth': cv2.OdometryType_RGB_DEPTH,
             'depth': cv2.OdometryType_DEPTH}
    odometry = cv2.Odometry(types[kind], settings, cv2.OdometryAlgoType_COMMON)
    grey = [cv2.cvtColor(f['bgr'], cv2.COLOR_BGR2GRAY) for f in frames]
    depth = [f['depth_mm'].astype(np.float32) / 1000.0 for f in frames]
    relative, times, lost = [], [], 0
    for k in range(1, len(frames)):
        t0 = time.perf_counter()
        if kind == 'depth':
            ok, Rt = odometry.compute(depth[k], depth[k - 1])
        else:
            ok, Rt = odometry.compute(depth[k], grey[k], depth[k - 1], grey[k - 1])
        times.append(1000.0 * (time.perf_counter() - t0))
        relative.append(np.asarray(Rt) if ok else None)  # Rt * src(k) = dst(k - 1)
        lost += not ok
    return chain(relative), times, lost


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('--frames', required=True)
    p.add_argument('--ours', required=True)
    p.add_argument('--out', required=True)
    a = p.parse_args()
    try:
        K, frames = load_frames(a.frames)
        import open3d  # noqa: F401
    except Exception as e:  # a package or the frames are missing
        print('vo_real: %s' % e, file=sys.stderr)
        return 1
    if len(frames) < 2:
        print('vo_real: no frames in %s' % a.frames, file=sys.stderr)
        return 1
    truth = [f['pose'][:3, 3] for f in frames]
    ours = json.load(open(a.ours))
    rows = [{'method': 'GeoFusion visual odometry (ORB, local map)', 'ate_m': ours['ate_rmse_m'],
             'lost': ours['lost_frames'], 'median_ms': ours['time_ms_median']}]
    runs = [('Open3D 0.20 RGB-D odometry (hybrid)', lambda: run_open3d(K, frames))]
    for kind in ('rgb', 'rgb_depth', 'depth'):
        runs.append(('OpenCV 5 Odometry %s' % kind.replace('_', ' + '),
                     lambda kind=kind: run_opencv(K, frames, kind)))
    for name, run in runs:
        poses, times, lost = run()
        rows.append({'method': name, 'ate_m': umeyama_ate([q[:3, 3] for q in poses], truth),
                     'lost': lost, 'median_ms': float(np.median(times))})
        print('vo_real: %s: ATE %.2f cm, %d lost, %.1f ms a frame' %
              (name, 100 * rows[-1]['ate_m'], lost, rows[-1]['median_ms']))
    os.makedirs(a.out, exist_ok=True)
    json.dump({'format': 'geofusion_vo_real_v1', 'frames': len(frames), 'rows': rows},
              open(os.path.join(a.out, 'vo_real.json'), 'w'), indent=1)
    with open(os.path.join(a.out, 'vo_real.md'), 'w') as f:
        f.write('| method (one thread, frame to frame unless said) | ATE RMSE | lost | median ms a '
                'frame |\n|---|---:|---:|---:|\n')
        for r in rows:
            f.write('| %s | %.2f cm | %d | %.1f |\n' % (r['method'], 100 * r['ate_m'], r['lost'],
                                                      r['median_ms']))
    print('vo_real: %s' % os.path.join(a.out, 'vo_real.md'))
    return 0


if __name__ == '__main__':
    sys.exit(main())
