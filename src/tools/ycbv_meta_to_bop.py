#!/usr/bin/env python3
"""ycbv_meta_to_bop: writes a YCB-Video video folder's ground truth (NNNNNN-meta.mat, read with
SciPy) as BOP's scene_camera.json and scene_gt.json beside it, the files import_dataset reads
(docs/dataset.md, "Real recordings").

    ycbv_meta_to_bop.py VIDEO_DIR [--out-dir DIR]

Per frame: cam_K from intrinsic_matrix, depth_scale = 1000 / factor_depth (mm per unit),
ycbv_rotation_translation_matrix_3x4 (world -> camera, metres) from rotation_translation_matrix;
per object obj_id = cls_indexes, cam_R_m2c (row-major) and cam_t_m2c (mm) from poses.
Exit 0 on success, 1 when a meta file cannot be read or is malformed, 2 on bad arguments."""
import argparse
import glob
import json
import os
import sys


def frame_of(path):
    import numpy as np
    import scipy.io
    meta = scipy.io.loadmat(path)
    K = np.asarray(meta['intrinsic_matrix'], dtype=float)
    factor = float(np.asarray(meta['factor_depth']).ravel()[0])
    poses = np.asarray(meta['poses'], dtype=float)
    if poses.ndim == 2:
        poses = poses[:, :, None]
    ids = np.asarray(meta['cls_indexes']).ravel().astype(int)
    if K.shape != (3, 3) or poses.shape[:2] != (3, 4) or poses.shape[2] != len(ids) or factor <= 0:
        raise ValueError('unexpected shapes (intrinsic_matrix %s, poses %s, %d classes)' %
                         (K.shape, poses.shape, len(ids)))
    camera = {'cam_K': K.ravel().tolist(), 'depth_scale': 1000.0 / factor}
    if 'rotation_translation_matrix' in meta:
        camera['ycbv_rotation_translation_matrix_3x4'] = \
            np.asarray(meta['rotation_translation_matrix'], dtype=float).tolist()
    objects = [{'obj_id': int(ids[k]), 'cam_R_m2c': poses[:, :3, k].ravel().tolist(),
                'cam_t_m2c': (1000.0 * poses[:, 3, k]).tolist()} for k in range(len(ids))]
    return camera, objects


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('video_dir')
    parser.add_argument('--out-dir', default=None, help='default: the video folder')
    args = parser.parse_args()
    metas = sorted(glob.glob(os.path.join(args.video_dir, '[0-9]*-meta.mat')))
    if not metas:
        print('ycbv_meta_to_bop: no NNNNNN-meta.mat in %s' % args.video_dir, file=sys.stderr)
        return 1
    cameras, gt = {}, {}
    for path in metas:
        im_id = str(int(os.path.basename(path).split('-')[0]))
        try:
            cameras[im_id], gt[im_id] = frame_of(path)
        except Exception as e:  # scipy raises many kinds on a corrupt file
            print('ycbv_meta_to_bop: %s: %s' % (path, e), file=sys.stderr)
            return 1
    out = args.out_dir or args.video_dir
    os.makedirs(out, exist_ok=True)
    for name, data in (('scene_camera.json', cameras), ('scene_gt.json', gt)):
        tmp = os.path.join(out, name + '.tmp')
        with open(tmp, 'w') as f:
            json.dump(data, f)
        os.replace(tmp, os.path.join(out, name))
    print('ycbv_meta_to_bop: %d frames -> %s' % (len(metas), out))
    return 0


if __name__ == '__main__':
    sys.exit(main())
