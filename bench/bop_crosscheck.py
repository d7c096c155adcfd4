#!/usr/bin/env python3
"""Cross-check of GeoFusion's BOP metrics against BOP's reference toolkit (issue 51, one-off).

The package computes BOP's MSSD and MSPD itself (src/evaluation/bop_metrics.cpp, per estimate,
in evaluate_run's JSON) and their recall and average recall (src/tools/bench_report.py,
bop_metrics). This script scores the same run with BOP's own toolkit (thodan/bop_toolkit:
scripts/eval_calc_errors.py and scripts/eval_calc_scores.py) and prints both side by side:

    bop_crosscheck.py --dataset DIR --results geofusion_ycbv-test.csv [...]
                      --bop-toolkit DIR [--eval geofusion_eval.json ...] [--work DIR]
                      [--method NAME] [--python PYTHON] [--summary OUT.json]
                      [--bop-models-info models_info.json]

The toolkit is fetched separately (a checkout or `git archive` of its repository, given with
--bop-toolkit); it is not part of this package and nothing of it is copied here. It needs numpy
(< 2), scipy, pypng and imageio in the Python that runs this script (or --python); the
package's own bop_metrics is imported from bench_report.py in this process (matplotlib and
pycocotools, which bench_report.py imports but bop_metrics does not use, are replaced by empty
stand-ins when missing).

What it does:
  1. Takes the BOP dataset the package wrote for the run (evaluate_run --bop-dataset DIR, or
     `make bench`'s <out>/bop/ycbv: evaluation/bop_dataset.h; its folder must be named ycbv, the
     toolkit's parameters for it are used): the ground truth at the keyframes in BOP's model
     frame, models_eval (points and models_info.json with the model set's appearance
     symmetries), BOP19's targets and geofusion_ids.json (scenes, image sizes, the truth object
     of each gt_id). It is copied into --work; with --bop-models-info (BOP's own ycbv
     models_info.json) its diameters and symmetries replace the package's there: how far the
     package's numbers are from BOP's official scoring of the same poses (the points stay the
     YCB-Video evaluation points, not BOP's meshes).
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

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
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

def load_dataset(root):
    """The package's BOP dataset (evaluate_run --bop-dataset): {'models': {obj_id: {name, pts
    (mm, BOP frame)}}, 'scenes': {scene_id: {name, K, width, height, images: [im_id],
    gt_objects: {im_id: [truth object index per gt_id]}}}, 'targets': [...]}."""
    def read(path):
        with open(os.path.join(root, path)) as f:
            return json.load(f)
    if os.path.basename(os.path.normpath(root)) != DATASET:
        raise CheckError("%s: the dataset folder must be named %s (the toolkit's parameters "
                         "for it are used)" % (root, DATASET))
    ids = read('geofusion_ids.json')
    models = {}
    for obj_id, name in ids.get('obj_ids', {}).items():
        ply = os.path.join(root, 'models_eval', 'obj_%06d.ply' % int(obj_id))
        with open(ply) as f:
            header = 0
            for line in f:
                header += 1
                if line.strip() == 'end_header':
                    break
        models[int(obj_id)] = {'name': name, 'pts': np.loadtxt(ply, skiprows=header, dtype=float,
                                                               ndmin=2)}
    scenes = {}
    for sid, sc in ids.get('scenes', {}).items():
        sid = int(sid)
        camera = read(os.path.join(SPLIT, '%06d' % sid, 'scene_camera.json'))
        first = camera[min(camera, key=int)]
        scenes[sid] = {'name': sc['name'], 'width': int(sc['width']),
                       'height': int(sc['height']),
                       'K': np.array(first['cam_K'], float).reshape(3, 3),
                       'images': sorted(int(i) for i in sc['images']),
                       'gt_objects': {int(i): v for i, v in sc['gt_objects'].items()}}
    if not scenes:
        raise CheckError('%s: no scene in geofusion_ids.json' % root)
    return {'models': models, 'scenes': scenes, 'targets': read(TARGETS_FILE)}


def copy_dataset(root, work_datasets, bop_models_info=None):
    """The dataset copied into the toolkit's datasets folder, with BOP's models_info.json's
    diameters and symmetries put in where given."""
    target = os.path.join(work_datasets, DATASET)
    shutil.copytree(root, target)
    if not bop_models_info:
        return
    with open(bop_models_info) as f:
        official = json.load(f)
    path = os.path.join(target, 'models_eval', 'models_info.json')
    with open(path) as f:
        info = json.load(f)
    for obj_id, entry in info.items():
        if obj_id not in official:
            raise CheckError('%s: no object %s' % (bop_models_info, obj_id))
        for key in ('diameter', 'symmetries_discrete', 'symmetries_continuous'):
            entry.pop(key, None)
            if key in official[obj_id]:
                entry[key] = official[obj_id][key]
    with open(path, 'w') as f:
        json.dump(info, f, indent=1)


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


def load_evals(paths, scenes):
    """{scene_id: evaluation} of evaluate_run --json files, by the dataset's scene names."""
    id_of = {sc['name']: sid for sid, sc in scenes.items()}
    evals = {}
    for path in paths:
        with open(path) as f:
            ev = json.load(f)
        if ev.get('format') != 'geofusion_evaluation_v1':
            raise CheckError('%s: not a geofusion_evaluation_v1 file' % path)
        sid = id_of.get(ev.get('scene'))
        if sid is None:
            raise CheckError('%s: scene %s is not in the dataset' % (path, ev.get('scene')))
        if sid in evals:
            raise CheckError('%s: scene %s twice' % (path, ev.get('scene')))
        ev['_path'] = path
        evals[sid] = ev
    return evals


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

def match_estimates(rows, evals, scenes, models, box_tol=0.5, score_tol=6e-7):
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
        sc = scenes[sid]
        box = projected_box(models[r['obj_id']]['pts'], r['R'], r['t'], sc['K'], sc['width'],
                            sc['height'])
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
    ap.add_argument('--dataset', required=True,
                    help='BOP dataset folder named ycbv of evaluate_run --bop-dataset')
    ap.add_argument('--results', action='append', required=True,
                    help='BOP results CSV of run_offline --bop-results (repeatable)')
    ap.add_argument('--bop-toolkit', required=True, help='bop_toolkit checkout')
    ap.add_argument('--eval', action='append', default=[],
                    help="evaluate_run --json of the same run (repeatable: one per scene)")
    ap.add_argument('--method', help='method name in the result file name (default: the first '
                    "CSV's name up to '_')")
    ap.add_argument('--work', default='/tmp/bopcheck/work', help='scratch folder (emptied)')
    ap.add_argument('--python', default=sys.executable,
                    help='Python that runs the toolkit (default: this one)')
    ap.add_argument('--summary', help='also write the numbers to this JSON file')
    ap.add_argument('--bop-models-info', help="BOP's models_info.json: its diameters and "
                    "symmetries instead of the package's")
    args = ap.parse_args(argv)

    try:
        dataset = load_dataset(args.dataset)
        models, scenes, targets = dataset['models'], dataset['scenes'], dataset['targets']
        evals = load_evals(args.eval, scenes)
        notes = []
        widths = {sc['width'] for sc in scenes.values()}
        if widths != {640}:
            notes.append('image width %s: the toolkit scales MSPD by 640 / the ycbv width (640), '
                         'the package by its own width / 640' % sorted(widths))

        rows = load_results(args.results)
        known = {(sid, im) for sid, sc in scenes.items() for im in sc['images']}
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
        toolkit = Toolkit(args.bop_toolkit, args.python, work, scenes)
        if os.path.exists(work):
            shutil.rmtree(work)
        for sub in ('datasets', 'results', 'eval'):
            os.makedirs(os.path.join(work, sub))
        copy_dataset(args.dataset, os.path.join(work, 'datasets'), args.bop_models_info)
        gt_objects = {sid: sc['gt_objects'] for sid, sc in scenes.items()}
        method = args.method or os.path.basename(args.results[0]).split('_')[0]
        method = re.sub(r'[^A-Za-z0-9-]', '', method) or 'method'
        result_filename = '%s_%s-%s.csv' % (method, DATASET, SPLIT)
        with open(os.path.join(work, 'results', result_filename), 'w') as f:
            f.write(HEADER + '\n' + ''.join(r['line'] + '\n' for r in rows))

        print('BOP cross-check: %s, %d scene(s) %s, %d images, %d targets (%d instances), '
              '%d estimates' % (method, len(scenes), sorted(scenes), len(known),
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

        summary = {'method': method, 'scenes': sorted(scenes), 'notes': notes}
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
            matched, no_match, package_only = match_estimates(rows, evals, scenes, models)
            cmp = compare_errors(error_dirs, matched, evals, gt_objects, sorted(scenes))
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
    except (CheckError, OSError, ValueError, KeyError) as e:
        print('bop_crosscheck: %s' % e, file=sys.stderr)
        return 1


if __name__ == '__main__':
    sys.exit(main())
