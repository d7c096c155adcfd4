#!/usr/bin/env python3
"""Cross-check of GeoFusion's BOP metrics against BOP's reference toolkit (issue 51, one-off).

The package computes BOP's MSSD and MSPD itself (src/evaluation/bop_metrics.cpp, per estimate,
in evaluate_run's JSON) and their recall and average recall (src/tools/bench_report.py,
bop_metrics). This script scores the same run with BOP's own toolkit (thodan/bop_toolkit:
scripts/eval_calc_errors.py and scripts/eval_calc_scores.py) and prints both side by side:

    bop_crosscheck.py --gt bench_01_gt.yaml [--gt ...] --results geofusion_ycbv-test.csv [...]
                      --models /work/shared/data/ycb_video --bop-toolkit DIR
                      [--eval geofusion_eval.json ...] [--work DIR] [--method NAME]
                      [--model-set config/models/ycb_video.yaml] [--python PYTHON]
                      [--summary OUT.json] [--bop-models-info models_info.json]

The toolkit is fetched separately (a checkout or `git archive` of its repository, given with
--bop-toolkit); it is not part of this package and nothing of it is copied here. It needs numpy
(< 2), scipy, pypng and imageio in the Python that runs this script (or --python), which also
needs PyYAML; the
package's own bop_metrics is imported from bench_report.py in this process (matplotlib and
pycocotools, which bench_report.py imports but bop_metrics does not use, are replaced by empty
stand-ins when missing).

What it does:
  1. Builds a temporary BOP dataset "ycbv" (test split) in --work from the ground-truth files
     (format geofusion_ground_truth_v1, docs/dataset.md): one scene per file, scene_id the number
     at the end of the scene's name (bench_03 -> 3, what run_offline's --bop-scene-id must have
     been); its images are the keyframes, im_id the keyframe's index (its order among the
     keyframes; with --eval, the evaluation's image of the same stamp); scene_camera.json (cam_K of
     the intrinsics, depth_scale 1), scene_gt.json (every object present at that frame, its pose in
     the keyframe's TRUE camera frame and BOP's model frame, T_cam_obj x Translation(box centre),
     t in mm), scene_gt_info.json (visib_fract: the file's visible fraction) and
     test_targets_bop19.json (objects at least 10 % visible, inst_count per image and object).
     models_eval/: obj_XXXXXX.ply (the YCB-Video evaluation points, mm, in BOP's frame: origin at
     the centre of their bounding box) and models_info.json (diameter: the largest distance
     between two points, as bop_metrics.cpp; symmetries: the model set's `appearance_symmetry`,
     else its `symmetry`, turning about BOP's origin (offset 0), as the package scores them).
     With --bop-models-info (BOP's own ycbv models_info.json) its diameters and symmetries are
     used instead: how far the package's numbers are from BOP's official scoring of the same
     poses (the points stay the YCB-Video evaluation points, not BOP's meshes).
  2. Concatenates the BOP results CSVs (run_offline --bop-results) into one
     <method>_ycbv-test.csv and runs eval_calc_errors.py (mssd, mspd; n_top -1: the ViVo task)
     and eval_calc_scores.py at BOP19's thresholds (MSSD 0.05-0.5 of the diameter, MSPD 5-50 px,
     the toolkit scaling by 640 / image width), as eval_bop19_pose.py does. The toolkit's ycbv
     test scenes are 48-59: its scene list is replaced by ours (a wrapper around the scripts).
  3. Prints the toolkit's recall per threshold, AR_MSSD and AR_MSPD; with --eval (evaluate_run
     --json of the same run, one per scene) also the package's (bench_report.bop_metrics, and
     per threshold with its _bop_match), their differences, and per estimate the largest
     difference of MSSD (mm) and MSPD (px) between the two, estimates matched by image, object
     and pose (the score and the projected box of the CSV's pose against the evaluation's).

Exit code: 0 when it ran, 1 on an error.
"""
import argparse
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
import types

import numpy as np
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DEFAULT_MODEL_SET = os.path.join(REPO, 'config', 'models', 'ycb_video.yaml')
BENCH_REPORT = os.path.join(REPO, 'src', 'tools', 'bench_report.py')

DATASET, SPLIT = 'ycbv', 'test'
TARGETS_FILE = 'test_targets_bop19.json'
VISIB_MIN = 0.1                                  # BOP19 targets: at least 10 % visible
MAX_SYM_DISC_STEP = 0.01                         # eval_bop19_pose.py's
THRESHOLDS = {                                   # eval_bop19_pose.py's, as it writes them
    'mssd': [float(x) for x in np.arange(0.05, 0.51, 0.05)],   # fraction of the diameter
    'mspd': [float(x) for x in np.arange(5, 51, 5)],           # px at an image 640 wide
}
HEADER = 'scene_id,im_id,obj_id,score,R,t,time'

# Runs one toolkit script with the dataset's scene list replaced by ours: the toolkit fixes the
# ycbv test scenes to 48-59 and its scores index per-scene counts by that list.
TOOLKIT_RUNNER = r'''
import runpy, sys
from bop_toolkit_lib import dataset_params
_get_split_params = dataset_params.get_split_params
_scene_ids = [int(s) for s in sys.argv[1].split(",")]
def _our_scenes(*args, **kwargs):
    p = _get_split_params(*args, **kwargs)
    p["scene_ids"] = list(_scene_ids)
    return p
dataset_params.get_split_params = _our_scenes
script = sys.argv[2]
sys.argv = [script] + sys.argv[3:]
runpy.run_path(script, run_name="__main__")
'''


class CheckError(Exception):
    """Input that cannot be used, or a step that failed."""


# ---------------------------------------------------------------------------------------------
# Geometry

def pose_matrix(p):
    """[x, y, z, qx, qy, qz, qw] -> 4x4."""
    x, y, z, qx, qy, qz, qw = (float(v) for v in p)
    n = np.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    qx, qy, qz, qw = qx / n, qy / n, qz / n, qw / n
    T = np.eye(4)
    T[:3, :3] = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
                 [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
                 [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
    T[:3, 3] = [x, y, z]
    return T


def rotation(axis, angle_deg):
    """Rotation matrix about `axis` (Rodrigues)."""
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    t = np.radians(float(angle_deg))
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * K @ K


def max_pairwise_distance(points, chunk=512):
    best = 0.0
    for i in range(0, len(points), chunk):
        d2 = ((points[i:i + chunk, None, :] - points[None, :, :]) ** 2).sum(-1)
        best = max(best, float(d2.max()))
    return float(np.sqrt(best))


def projected_box(pts_mm, R, t_mm, K, width, height):
    """evaluate_run's projectedBox: the points in front (z > 1 cm) projected, the box clamped to
    the image; [x, y, w, h] or None."""
    q = pts_mm @ R.T + t_mm
    q = q[q[:, 2] > 10.0]
    if not len(q):
        return None
    u = K[0, 0] * q[:, 0] / q[:, 2] + K[0, 2]
    v = K[1, 1] * q[:, 1] / q[:, 2] + K[1, 2]
    x0, x1 = np.clip([u.min(), u.max()], 0, width)
    y0, y1 = np.clip([v.min(), v.max()], 0, height)
    if x1 <= x0 or y1 <= y0:
        return None
    return [x0, y0, x1 - x0, y1 - y0]


# ---------------------------------------------------------------------------------------------
# Inputs

def load_models(models_dir, model_set_path, bop_models_info=None):
    """{obj_id: {name, pts (mm, BOP frame), centre_m, info (models_info.json entry)}}: class id k
    is line k of classes.txt; the symmetries are the model set's appearance symmetries, the
    diameter the points'; or both from `bop_models_info` (a models_info.json) when given."""
    official = None
    if bop_models_info:
        with open(bop_models_info) as f:
            official = {int(k): v for k, v in json.load(f).items()}
    with open(os.path.join(models_dir, 'classes.txt')) as f:
        names = [line.strip() for line in f if line.strip()]
    with open(model_set_path) as f:
        model_set = {c['name']: c for c in yaml.safe_load(f)['classes']}
    models = {}
    for obj_id, name in enumerate(names, 1):
        pts_m = np.loadtxt(os.path.join(models_dir, name, 'points.xyz'), dtype=float, ndmin=2)
        lo, hi = pts_m.min(0), pts_m.max(0)
        centre = 0.5 * (lo + hi)
        pts = 1000.0 * (pts_m - centre)
        info = {'diameter': max_pairwise_distance(pts)}
        for axis, a, b in zip('xyz', 1000.0 * (lo - centre), 1000.0 * (hi - centre)):
            info['min_' + axis], info['size_' + axis] = float(a), float(b - a)
        entry = model_set.get(name)
        if entry is None:
            raise CheckError('%s: class %s not in %s' % (models_dir, name, model_set_path))
        sym = entry.get('appearance_symmetry', entry.get('symmetry'))
        if isinstance(sym, dict) and sym.get('type') == 'discrete':
            info['symmetries_discrete'] = []
            for r in sym['rotations']:
                S = np.eye(4)
                S[:3, :3] = rotation(r['axis'], r['angle_deg'])
                info['symmetries_discrete'].append([float(v) for v in S.flatten()])
        elif isinstance(sym, dict) and sym.get('type') == 'continuous':
            a = np.asarray(sym['axis'], float)
            info['symmetries_continuous'] = [{'axis': [float(v) for v in a / np.linalg.norm(a)],
                                              'offset': [0.0, 0.0, 0.0]}]
        elif sym not in (None, 'none') and not (isinstance(sym, dict)
                                                and sym.get('type') == 'none'):
            raise CheckError('%s: symmetry of %s not understood: %r' % (model_set_path, name, sym))
        if official is not None:
            if obj_id not in official:
                raise CheckError('%s: no object %d' % (bop_models_info, obj_id))
            for key in ('diameter', 'symmetries_discrete', 'symmetries_continuous'):
                info.pop(key, None)
                if key in official[obj_id]:
                    info[key] = official[obj_id][key]
        models[obj_id] = {'name': name, 'pts': pts, 'centre_m': centre, 'info': info}
    return models


def scene_id_of(name):
    m = re.search(r'(\d+)$', str(name))
    if not m:
        raise CheckError('scene name %r does not end in a number (the BOP scene id)' % name)
    return int(m.group(1))


def load_ground_truth(path):
    """The parts of a geofusion_ground_truth_v1 file the BOP dataset needs."""
    loader = getattr(yaml, 'CSafeLoader', yaml.SafeLoader)
    with open(path) as f:
        gt = yaml.load(f, Loader=loader)
    if not isinstance(gt, dict) or gt.get('format') != 'geofusion_ground_truth_v1':
        raise CheckError('%s: not a geofusion_ground_truth_v1 file' % path)
    if gt.get('model_set') != 'ycb_video':
        raise CheckError('%s: model set %r, not ycb_video' % (path, gt.get('model_set')))
    k = gt['intrinsics']
    objects = [{'index': int(o['index']), 'class_id': int(o['class_id']),
                'class_name': o['class_name'], 'T_map_obj': pose_matrix(o['pose']),
                'from': int(o.get('present_from_frame', 0)),
                'until': int(o.get('present_until_frame', -1))} for o in gt['objects']]
    keyframes = [{'frame': int(f['index']), 'stamp': float(f['stamp']),
                  'T_map_cam': pose_matrix(f['map_camera']),
                  'visible_fraction': [float(v) for v in f.get('visible_fraction') or []],
                  'visible_pixels': [int(v) for v in f.get('visible_pixels') or []],
                  'visible_boxes': f.get('visible_boxes') or []}
                 for f in gt['frames'] if f.get('keyframe')]
    return {'path': path, 'scene': gt['scene'], 'scene_id': scene_id_of(gt['scene']),
            'width': int(k['width']), 'height': int(k['height']),
            'K': np.array([[k['fx'], 0, k['cx']], [0, k['fy'], k['cy']], [0, 0, 1]], float),
            'objects': objects, 'keyframes': keyframes}


def load_results(paths):
    """The CSV rows, in order, each with est_id: its index among the rows of the same scene,
    image and object (the toolkit's est_id)."""
    rows, counts = [], {}
    for path in paths:
        with open(path) as f:
            lines = f.read().splitlines()
        if not lines or lines[0].strip() != HEADER:
            raise CheckError('%s: not a BOP results CSV (header %r)' % (path, HEADER))
        for n, line in enumerate(lines[1:], 2):
            if not line.strip():
                continue
            e = line.split(',')
            if len(e) != 7:
                raise CheckError('%s:%d: not 7 fields' % (path, n))
            row = {'scene_id': int(e[0]), 'im_id': int(e[1]), 'obj_id': int(e[2]),
                   'score': float(e[3]), 'R': np.array(e[4].split(), float).reshape(3, 3),
                   't': np.array(e[5].split(), float), 'time': float(e[6]), 'line': line}
            key = (row['scene_id'], row['im_id'], row['obj_id'])
            row['est_id'] = counts.get(key, 0)
            counts[key] = row['est_id'] + 1
            rows.append(row)
    return rows


def load_evals(paths):
    """{scene_id: evaluation} of evaluate_run --json files."""
    evals = {}
    for path in paths:
        with open(path) as f:
            ev = json.load(f)
        if ev.get('format') != 'geofusion_evaluation_v1':
            raise CheckError('%s: not a geofusion_evaluation_v1 file' % path)
        sid = scene_id_of(ev.get('scene'))
        if sid in evals:
            raise CheckError('%s: scene %s twice' % (path, ev.get('scene')))
        ev['_path'] = path
        evals[sid] = ev
    return evals


# ---------------------------------------------------------------------------------------------
# The BOP dataset

def image_ids(gt, ev):
    """[(im_id, keyframe)]: by order among the keyframes; with the scene's evaluation, by stamp
    (its images are the run's keyframes: id = keyframe index), checked against the order."""
    by_order = list(enumerate(gt['keyframes']))
    if ev is None:
        return by_order, []
    notes = []
    kf_by_stamp = {round(k['stamp'], 4): k for k in gt['keyframes']}
    out = []
    for image in ev.get('images') or []:
        k = kf_by_stamp.get(round(float(image['stamp']), 4))
        if k is None:
            notes.append('image %s (stamp %.4f) is no keyframe of the ground truth'
                         % (image['id'], image['stamp']))
            continue
        out.append((int(image['id']), k))
    order = {id(k): i for i, k in by_order}
    moved = [(i, order[id(k)]) for i, k in out if order[id(k)] != i]
    if moved:
        notes.append('%d images whose id is not their order among the keyframes (first: id %d, '
                     'order %d)' % (len(moved), moved[0][0], moved[0][1]))
    if len(out) != len(by_order):
        notes.append('%d keyframes in the ground truth, %d images in the evaluation'
                     % (len(by_order), len(out)))
    return out, notes


def write_dataset(root, scenes, models):
    """Writes the temporary BOP dataset under root/ycbv. Returns ({scene_id: {im_id: [object
    index per gt_id]}} (the toolkit's gt_id -> ground-truth object), the targets)."""
    base = os.path.join(root, DATASET)
    if os.path.exists(base):
        shutil.rmtree(base)
    models_dir = os.path.join(base, 'models_eval')
    os.makedirs(models_dir)
    for obj_id, m in models.items():
        with open(os.path.join(models_dir, 'obj_%06d.ply' % obj_id), 'w') as f:
            f.write('ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n'
                    'property float z\nend_header\n' % len(m['pts']))
            for p in m['pts']:
                f.write('%.6f %.6f %.6f\n' % tuple(p))
    with open(os.path.join(models_dir, 'models_info.json'), 'w') as f:
        json.dump({str(i): m['info'] for i, m in models.items()}, f, indent=1)

    targets, gt_objects = [], {}
    for sc in scenes:
        gt, sid = sc['gt'], sc['gt']['scene_id']
        K = gt['K']
        scene_camera, scene_gt, scene_gt_info = {}, {}, {}
        gt_objects[sid] = {}
        for im_id, kf in sc['images']:
            T_cam_map = np.linalg.inv(kf['T_map_cam'])
            im_gt, im_info, index = [], [], []
            inst = {}
            for o in gt['objects']:
                i = o['index']
                if not (kf['frame'] >= o['from'] and (o['until'] < 0 or kf['frame'] < o['until'])):
                    continue                                  # not in the scene at that frame
                m = models[o['class_id']]
                T = T_cam_map @ o['T_map_obj']
                t_bop = T[:3, :3] @ m['centre_m'] + T[:3, 3]  # T x Translation(box centre)
                im_gt.append({'obj_id': o['class_id'],
                              'cam_R_m2c': [float(v) for v in T[:3, :3].flatten()],
                              'cam_t_m2c': [float(v) for v in 1000.0 * t_bop]})
                vf = kf['visible_fraction'][i] if i < len(kf['visible_fraction']) else 0.0
                px = kf['visible_pixels'][i] if i < len(kf['visible_pixels']) else 0
                box = kf['visible_boxes'][i] if i < len(kf['visible_boxes']) else [0, 0, 0, 0]
                im_info.append({'visib_fract': vf, 'px_count_visib': px,
                                'px_count_all': int(round(px / vf)) if vf > 0 else 0,
                                'bbox_visib': [int(v) for v in box] if px else [-1, -1, -1, -1]})
                index.append(i)
                if vf >= VISIB_MIN:
                    inst[o['class_id']] = inst.get(o['class_id'], 0) + 1
            scene_camera[str(im_id)] = {'cam_K': [float(v) for v in K.flatten()],
                                        'depth_scale': 1.0}
            scene_gt[str(im_id)] = im_gt
            scene_gt_info[str(im_id)] = im_info
            gt_objects[sid][im_id] = index
            targets += [{'scene_id': sid, 'im_id': im_id, 'obj_id': obj_id, 'inst_count': n}
                        for obj_id, n in sorted(inst.items())]
        scene_dir = os.path.join(base, SPLIT, '%06d' % sid)
        os.makedirs(scene_dir)
        for name, content in (('scene_camera.json', scene_camera), ('scene_gt.json', scene_gt),
                              ('scene_gt_info.json', scene_gt_info)):
            with open(os.path.join(scene_dir, name), 'w') as f:
                json.dump(content, f)
    with open(os.path.join(base, TARGETS_FILE), 'w') as f:
        json.dump(targets, f)
    return gt_objects, targets


# ---------------------------------------------------------------------------------------------
# The toolkit

class Toolkit:
    def __init__(self, toolkit_dir, python, work, scene_ids):
        self.dir = os.path.abspath(toolkit_dir)
        for script in ('eval_calc_errors.py', 'eval_calc_scores.py'):
            if not os.path.isfile(os.path.join(self.dir, 'scripts', script)):
                raise CheckError('%s: no scripts/%s (the bop_toolkit checkout)'
                                 % (self.dir, script))
        self.python = python
        self.work = work
        self.scene_ids = ','.join(str(s) for s in sorted(scene_ids))
        self.log = os.path.join(work, 'toolkit.log')
        self.env = dict(os.environ, PYTHONPATH=self.dir, BOP_PATH=os.path.join(work, 'datasets'),
                        BOP_RESULTS_PATH=os.path.join(work, 'results'),
                        BOP_EVAL_PATH=os.path.join(work, 'eval'), BOP_NUM_WORKERS='1')
        sys.path.insert(0, self.dir)
        from bop_toolkit_lib import misc  # noqa: E402 (the signatures of its file names)
        self.misc = misc

    def run(self, script, args):
        cmd = [self.python, '-c', TOOLKIT_RUNNER, self.scene_ids,
               os.path.join(self.dir, 'scripts', script)] + args
        with open(self.log, 'a') as log:
            log.write('\n$ %s\n' % ' '.join(cmd[:2] + ['RUNNER'] + cmd[3:]))
            log.flush()
            rc = subprocess.call(cmd, env=self.env, stdout=log, stderr=subprocess.STDOUT)
        if rc != 0:
            with open(self.log) as log:
                tail = log.read().splitlines()[-25:]
            raise CheckError('%s failed (exit %d); the end of %s:\n%s'
                             % (script, rc, self.log, '\n'.join(tail)))

    def evaluate(self, result_filename, error_type):
        """eval_calc_errors + eval_calc_scores at each BOP19 threshold, as eval_bop19_pose.py
        runs them; returns (recalls, error_dir)."""
        result_name = result_filename.rsplit('.', 1)[0]
        common = ['--eval_path=' + self.env['BOP_EVAL_PATH'],
                  '--datasets_path=' + self.env['BOP_PATH'],
                  '--targets_filename=' + TARGETS_FILE]
        self.run('eval_calc_errors.py', common + [
            '--n_top=-1', '--error_type=' + error_type, '--result_filenames=' + result_filename,
            '--results_path=' + self.env['BOP_RESULTS_PATH'],
            '--max_sym_disc_step=%s' % MAX_SYM_DISC_STEP, '--skip_missing=1', '--num_workers=1'])
        error_sign = self.misc.get_error_signature(error_type, -1)
        error_dir = os.path.join(result_name, error_sign)
        recalls = []
        for th in THRESHOLDS[error_type]:
            self.run('eval_calc_scores.py', common + [
                '--error_dir_paths=' + error_dir, '--visib_gt_min=-1',
                '--correct_th_%s=%s' % (error_type, th)])
            sign = self.misc.get_score_signature([th], -1)
            with open(os.path.join(self.env['BOP_EVAL_PATH'], error_dir,
                                   'scores_%s.json' % sign)) as f:
                scores = json.load(f)
            recalls.append({'recall': scores['recall'], 'tp': scores['tp_count'],
                            'targets': scores['targets_count']})
        return recalls, os.path.join(self.env['BOP_EVAL_PATH'], error_dir)


# ---------------------------------------------------------------------------------------------
# The package's numbers

def import_bench_report():
    """bench_report.py, with empty stand-ins for matplotlib and pycocotools where they are
    missing (bop_metrics uses neither)."""
    class Stub(types.ModuleType):
        def __getattr__(self, name):
            if name.startswith('__'):
                raise AttributeError(name)
            return lambda *args, **kwargs: None

    for top, subs in (('matplotlib', ('pyplot', 'lines')), ('pycocotools', ('coco', 'cocoeval'))):
        if importlib.util.find_spec(top) is None:
            sys.modules[top] = Stub(top)
            for sub in subs:
                sys.modules[top + '.' + sub] = Stub(top + '.' + sub)
    spec = importlib.util.spec_from_file_location('bench_report', BENCH_REPORT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def package_recalls(br, evals):
    """Per threshold, the package's matched targets over all targets: bop_metrics' grouping
    (non-crowd ground truth per image and class, the detections of that image and class) with
    its _bop_match."""
    hits = {'mssd': [0] * 10, 'mspd': [0] * 10}
    total = 0
    for ev in evals:
        diameters = {int(c['id']): c.get('diameter_m') or 0.0 for c in ev.get('categories') or []}
        width = float((ev.get('image_size') or [640, 480])[0]) or 640.0
        groups = {}
        for a in ev.get('annotations') or []:
            if not a.get('iscrowd'):
                key = (a['image_id'], int(a['category_id']))
                groups.setdefault(key, ([], []))[0].append(a['id'])
        for d in ev.get('detections') or []:
            key = (d['image_id'], int(d['category_id']))
            if key in groups:
                groups[key][1].append(d)
        for (_, cls), (targets, estimates) in groups.items():
            total += len(targets)
            diameter = diameters.get(cls, 0.0)
            for i, f in enumerate(br.BOP_MSSD_FRACTIONS):
                hits['mssd'][i] += br._bop_match(targets, estimates, 'mssd_m', f * diameter)
            for i, p in enumerate(br.BOP_MSPD_PIXELS):
                hits['mspd'][i] += br._bop_match(targets, estimates, 'mspd_px', p * width / 640.0)
    return {k: [{'recall': h / total if total else 0.0, 'tp': h, 'targets': total} for h in v]
            for k, v in hits.items()}


# ---------------------------------------------------------------------------------------------
# Per-estimate comparison

def match_estimates(rows, evals, scenes_by_id, models, box_tol=0.5, score_tol=6e-7):
    """{(scene_id, im_id, obj_id, est_id): detection of the evaluation} for the CSV rows: same
    image and class, same score (the CSV has 6 decimals) and the same projected box of the pose.
    Also the detections left unmatched in images and classes that have targets."""
    by_key = {}
    for sid, ev in evals.items():
        for d in ev.get('detections') or []:
            by_key.setdefault((sid, d['image_id'], int(d['category_id'])), []).append(d)
    matched, used, no_match = {}, set(), []
    for r in rows:
        sid = r['scene_id']
        if sid not in evals:
            continue
        gt = scenes_by_id[sid]['gt']
        box = projected_box(models[r['obj_id']]['pts'], r['R'], r['t'], gt['K'], gt['width'],
                            gt['height'])
        best, best_d = None, box_tol
        for d in by_key.get((sid, r['im_id'], r['obj_id']), []):
            if id(d) in used or abs(float(d['score']) - r['score']) > score_tol or box is None:
                continue
            diff = max(abs(a - b) for a, b in zip(box, d['bbox']))
            if diff <= best_d:
                best, best_d = d, diff
        if best is None:
            no_match.append(r)
        else:
            used.add(id(best))
            matched[(sid, r['im_id'], r['obj_id'], r['est_id'])] = best
    package_only = []
    for sid, ev in evals.items():
        targets = {(a['image_id'], int(a['category_id'])) for a in ev.get('annotations') or []
                   if not a.get('iscrowd')}
        package_only += [(sid, d) for d in ev.get('detections') or []
                         if id(d) not in used and (d['image_id'], int(d['category_id'])) in targets]
    return matched, no_match, package_only


def compare_errors(error_dirs, matched, evals, gt_objects, scene_ids):
    """Toolkit vs package error of every (estimate, ground truth) pair both computed."""
    out = {}
    for kind, key, scale in (('mssd', 'mssd_m', 1000.0), ('mspd', 'mspd_px', 1.0)):
        pairs, toolkit_inf, package_inf = [], 0, 0
        for sid in scene_ids:
            if sid not in evals:
                continue
            ann = {(a['image_id'], a['object']): a['id'] for a in evals[sid]['annotations']}
            with open(os.path.join(error_dirs[kind], 'errors_%06d.json' % sid)) as f:
                errors = json.load(f)
            for e in errors:
                d = matched.get((sid, e['im_id'], e['obj_id'], e['est_id']))
                if d is None:
                    continue
                for gt_id, values in e['errors'].items():
                    obj = gt_objects[sid][e['im_id']][int(gt_id)]
                    a = ann.get((e['im_id'], obj))
                    if a is None or str(a) not in d[key]:
                        continue                       # crowd or out of view: the package skips
                    theirs, ours = float(values[0]), d[key][str(a)]
                    if not np.isfinite(theirs):
                        toolkit_inf += 1               # the toolkit's "spheres do not overlap"
                        continue
                    if ours is None or not np.isfinite(ours):
                        package_inf += 1
                        continue
                    pairs.append((abs(theirs - scale * ours), theirs, scale * ours, sid,
                                  e['im_id'], e['obj_id'], obj))
        pairs.sort(key=lambda p: -p[0])
        diffs = np.array([p[0] for p in pairs]) if pairs else np.zeros(0)
        some = len(diffs) > 0
        out[kind] = {'pairs': len(pairs), 'max_abs_diff': float(diffs.max()) if some else None,
                     'mean_abs_diff': float(diffs.mean()) if some else None,
                     'over_0.01': int((diffs > 0.01).sum()), 'over_0.1': int((diffs > 0.1).sum()),
                     'over_1': int((diffs > 1.0).sum()),
                     'toolkit_inf_skipped': toolkit_inf, 'package_inf_skipped': package_inf,
                     'worst': [{'toolkit': p[1], 'package': p[2], 'scene_id': p[3], 'im_id': p[4],
                                'obj_id': p[5], 'gt_object': p[6]} for p in pairs[:5]]}
    return out


# ---------------------------------------------------------------------------------------------

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--gt', action='append', required=True, help='SCENE_gt.yaml (repeatable)')
    ap.add_argument('--results', action='append', required=True,
                    help='BOP results CSV of run_offline --bop-results (repeatable)')
    ap.add_argument('--models', required=True, help='YCB-Video models folder (classes.txt)')
    ap.add_argument('--bop-toolkit', required=True, help='bop_toolkit checkout')
    ap.add_argument('--eval', action='append', default=[],
                    help="evaluate_run --json of the same run (repeatable: one per scene)")
    ap.add_argument('--model-set', default=DEFAULT_MODEL_SET,
                    help='model set whose symmetries to use (default: %(default)s)')
    ap.add_argument('--method', help='method name in the result file name (default: the first '
                    "CSV's name up to '_')")
    ap.add_argument('--work', default='/tmp/bopcheck/work', help='scratch folder (emptied)')
    ap.add_argument('--python', default=sys.executable,
                    help='Python that runs the toolkit (default: this one)')
    ap.add_argument('--summary', help='also write the numbers to this JSON file')
    ap.add_argument('--bop-models-info', help="BOP's models_info.json: its diameters and "
                    "symmetries instead of the points' and the model set's")
    args = ap.parse_args(argv)

    try:
        models = load_models(args.models, args.model_set, args.bop_models_info)
        evals = load_evals(args.eval)
        scenes, notes = [], []
        for path in args.gt:
            gt = load_ground_truth(path)
            if any(s['gt']['scene_id'] == gt['scene_id'] for s in scenes):
                raise CheckError('%s: scene id %d twice' % (path, gt['scene_id']))
            images, n = image_ids(gt, evals.get(gt['scene_id']))
            notes += ['%s: %s' % (gt['scene'], x) for x in n]
            scenes.append({'gt': gt, 'images': images})
        scenes_by_id = {s['gt']['scene_id']: s for s in scenes}
        for sid in evals:
            if sid not in scenes_by_id:
                raise CheckError('%s: scene %d has no --gt' % (evals[sid]['_path'], sid))
        widths = {s['gt']['width'] for s in scenes}
        if widths != {640}:
            notes.append('image width %s: the toolkit scales MSPD by 640 / the ycbv width (640), '
                         'the package by its own width / 640' % sorted(widths))

        rows = load_results(args.results)
        known = {(sid, im) for sid, s in scenes_by_id.items() for im, _ in s['images']}
        stray = [r for r in rows if (r['scene_id'], r['im_id']) not in known]
        if stray:
            notes.append('%d result rows of images not in the dataset (first: scene %d, image %d)'
                         % (len(stray), stray[0]['scene_id'], stray[0]['im_id']))
        unknown = sorted({r['obj_id'] for r in rows} - set(models))
        if unknown:
            raise CheckError('result rows with obj_id %s, not a YCB-Video class' % unknown)
        times = {}
        for r in rows:
            times.setdefault((r['scene_id'], r['im_id']), set()).add(r['time'])
        if any(len(t) > 1 for t in times.values()):
            notes.append('rows of one image with different times (BOP requires one)')

        work = os.path.abspath(args.work)
        toolkit = Toolkit(args.bop_toolkit, args.python, work, scenes_by_id)
        if os.path.exists(work):
            shutil.rmtree(work)
        for sub in ('datasets', 'results', 'eval'):
            os.makedirs(os.path.join(work, sub))
        gt_objects, targets = write_dataset(os.path.join(work, 'datasets'), scenes, models)
        method = args.method or os.path.basename(args.results[0]).split('_')[0]
        method = re.sub(r'[^A-Za-z0-9-]', '', method) or 'method'
        result_filename = '%s_%s-%s.csv' % (method, DATASET, SPLIT)
        with open(os.path.join(work, 'results', result_filename), 'w') as f:
            f.write(HEADER + '\n' + ''.join(r['line'] + '\n' for r in rows))

        print('BOP cross-check: %s, %d scene(s) %s, %d images, %d targets (%d instances), '
              '%d estimates' % (method, len(scenes), sorted(scenes_by_id), len(known),
                                len(targets), sum(t['inst_count'] for t in targets), len(rows)))
        print('work folder: %s (toolkit log: toolkit.log)' % work)
        if args.bop_models_info:
            notes.append('diameters and symmetries from %s, not the package\'s: per-estimate '
                         'differences are expected where the symmetries differ'
                         % args.bop_models_info)
        for n in notes:
            print('note: ' + n)

        theirs, error_dirs = {}, {}
        for kind in ('mssd', 'mspd'):
            theirs[kind], error_dirs[kind] = toolkit.evaluate(result_filename, kind)

        ours, package_ar = None, None
        if evals:
            br = import_bench_report()
            ev_list = [evals[s] for s in sorted(evals)]
            package_ar = br.bop_metrics(ev_list)
            ours = package_recalls(br, ev_list)

        summary = {'method': method, 'scenes': sorted(scenes_by_id), 'notes': notes}
        for kind, label in (('mssd', 'MSSD (fraction of diameter)'), ('mspd', 'MSPD (px)')):
            print('\n%s recall per threshold:' % label)
            print('  %-8s %-22s %s' % ('th', 'toolkit (tp/targets)',
                                      'package (tp/targets)   diff' if ours else ''))
            for i, th in enumerate(THRESHOLDS[kind]):
                t = theirs[kind][i]
                line = '  %-8.3g %.4f (%d/%d)' % (th, t['recall'], t['tp'], t['targets'])
                if ours:
                    o = ours[kind][i]
                    line += '%s%.4f (%d/%d)  %+.4f' % (' ' * max(1, 24 - len(line)), o['recall'],
                                                      o['tp'], o['targets'],
                                                      o['recall'] - t['recall'])
                print(line)
            ar = float(np.mean([t['recall'] for t in theirs[kind]]))
            summary['toolkit_ar_' + kind] = ar
            summary['toolkit_recalls_' + kind] = theirs[kind]
            line = 'AR_%s: toolkit %.4f' % (kind.upper(), ar)
            if package_ar is not None:
                mine = package_ar.get('bop_ar_' + kind)
                summary['package_ar_' + kind] = mine
                summary['package_recalls_' + kind] = ours[kind]
                line += ', package %s' % ('n/a' if mine is None else '%.4f (diff %+.4f)'
                                          % (mine, mine - ar))
            print(line)

        if evals:
            matched, no_match, package_only = match_estimates(rows, evals, scenes_by_id, models)
            cmp = compare_errors(error_dirs, matched, evals, gt_objects, sorted(scenes_by_id))
            summary.update({'estimates_matched': len(matched),
                            'csv_rows_unmatched': len(no_match),
                            'package_detections_not_in_csv': len(package_only),
                            'per_estimate': cmp})
            print('\nper estimate: %d CSV rows matched to the evaluation\'s detections, %d not; '
                  '%d detections of images and classes with targets are not in the CSV'
                  % (len(matched), len(no_match), len(package_only)))
            for kind, unit in (('mssd', 'mm'), ('mspd', 'px')):
                c = cmp[kind]
                if not c['pairs']:
                    print('  %s: no pair to compare' % kind.upper())
                    continue
                print('  %s: %d (estimate, truth) pairs, max |toolkit - package| %.4g %s, mean '
                      '%.3g; over 0.01 / 0.1 / 1 %s: %d / %d / %d; skipped: toolkit inf %d, '
                      'package inf %d' % (kind.upper(), c['pairs'], c['max_abs_diff'], unit,
                                          c['mean_abs_diff'], unit, c['over_0.01'], c['over_0.1'],
                                          c['over_1'], c['toolkit_inf_skipped'],
                                          c['package_inf_skipped']))
                for w in c['worst'][:3]:
                    print('    scene %d image %d obj %d (truth object %d): toolkit %.4f, package '
                          '%.4f' % (w['scene_id'], w['im_id'], w['obj_id'], w['gt_object'],
                                    w['toolkit'], w['package']))
        if args.summary:
            with open(args.summary, 'w') as f:
                json.dump(summary, f, indent=1)
        return 0
    except (CheckError, OSError, ValueError, KeyError, yaml.YAMLError) as e:
        print('bop_crosscheck: %s' % e, file=sys.stderr)
        return 1


if __name__ == '__main__':
    sys.exit(main())
