"""The real frames' lift (issue 50), checked outside the package: the table plane fitted to the
real depth of each YCB-Video video's first frame (RANSAC on the background pixels of the label
image, then least squares; numpy), and each annotated object's lowest model point above it.
Reads ../shared/data/real and ../shared/data/ycb_video (GEOFUSION_REAL_DIR, GEOFUSION_YCB_DIR).
Usage: python3 bench/real_table_plane.py (figures in docs/stability.md)."""
import json, sys, numpy as np
from PIL import Image
import os
here = os.path.dirname(os.path.abspath(__file__))
root = os.environ.get('GEOFUSION_REAL_DIR', os.path.join(here, '../../shared/data/real')) + '/ycbv_video/'
ycb = os.environ.get('GEOFUSION_YCB_DIR', os.path.join(here, '../../shared/data/ycb_video'))
classes = open(ycb + '/classes.txt').read().split()
def load_obj(path):
    v = [list(map(float, l.split()[1:4])) for l in open(path) if l.startswith('v ')]
    return np.array(v)
rng = np.random.default_rng(0)
for video in ('0000', '0001'):
    gt = json.load(open(root + video + '/scene_gt.json')); cam = json.load(open(root + video + '/scene_camera.json'))
    k = sorted(gt, key=int)[0]; K = np.array(cam[k]['cam_K']).reshape(3, 3)
    d = np.array(Image.open(root + video + '/%06d-depth.png' % int(k))).astype(float) / 10000.0
    v, u = np.nonzero(d > 0); z = d[v, u]
    P = np.stack([(u - K[0, 2]) * z / K[0, 0], (v - K[1, 2]) * z / K[1, 1], z], 1)
    # mask object pixels with the label image (0 = background)
    lab = np.array(Image.open(root + video + '/%06d-label.png' % int(k)))
    bg = lab[v, u] == 0; Q = P[bg]
    best = None
    for _ in range(2000):
        s = Q[rng.choice(len(Q), 3, replace=False)]
        n = np.cross(s[1] - s[0], s[2] - s[0]); 
        if np.linalg.norm(n) < 1e-9: continue
        n /= np.linalg.norm(n); h = n @ s[0]
        inl = np.abs(Q @ n - h) < 0.005
        if best is None or inl.sum() > best[0]: best = (inl.sum(), n, h)
    _, n, h = best; inl = np.abs(Q @ n - h) < 0.005
    c = Q[inl].mean(0); w, E = np.linalg.eigh(np.cov((Q[inl] - c).T)); n = E[:, 0]; h = n @ c
    if n[1] > 0: n, h = -n, -h   # normal towards the camera side (up: image y points down)
    res = Q[inl] @ n - h
    print('%s frame %s: table plane from %d background points, residual rms %.1f mm' % (video, k, inl.sum(), 1000 * res.std()))
    for o in gt[k]:
        name = classes[o['obj_id'] - 1]
        V = load_obj('%s/%s/textured.obj' % (ycb, name))
        R = np.array(o['cam_R_m2c']).reshape(3, 3); t = np.array(o['cam_t_m2c']) / 1000.0
        W = V @ R.T + t
        print('   %-22s lowest point %.1f mm above the depth table' % (name, 1000 * (W @ n - h).min()))
