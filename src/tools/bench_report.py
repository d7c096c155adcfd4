#!/usr/bin/env python3
"""Benchmark report: reads the evaluation files of the four methods (FbF, B-SLAM, R-Front,
GeoFusion) on every scene of a suite and writes the paper's tables and figures.

    bench_report.py --eval-dir DIR --out OUTDIR [--suite NAME] [--commit SHA]
                    [--plot-scene SCENE] [--guard]
    bench_report.py --combine SUITE_DIR... --out OUTDIR   (one report over several suites)

Input: DIR/<scene>/<method_slug>.json, format "geofusion_evaluation_v1" (one file per method and
scene; the method's display name is the file's "method").

Measures, per method over all scenes pooled and per scene:
  * COCO bounding-box mAP (pycocotools): map50_95 = stats[0], map50 = stats[1], map75 = stats[2],
    in percent. Ground truth less than 10 % visible is marked iscrowd=1, so pycocotools ignores
    it: a detection on it is neither right nor wrong. Image and annotation ids are renumbered to
    be unique over the pooled scenes.
  * Precision and recall at score >= 0.5, at IoU 0.5 and 0.75, from pycocotools' own matching
    (COCOeval.evalImgs, area range 'all', 100 detections an image): a true positive is a
    detection matched to ground truth that is not ignored, a false positive an unmatched one that
    is not ignored, recall's denominator the ground truth that is not ignored. Thresholding the
    scores after the greedy by-score matching equals thresholding before it.
  * ADD-S of the true positives at IoU 0.5 (the evaluation file's adds_m of the detection against
    the matched annotation): share under 1 cm and 2 cm, the accuracy curve over [0, 2 cm], and the
    YCB-Video AUC up to 10 cm (percent), which counts one error per ground-truth instance that is
    not ignored, infinite when no true positive found it. A true positive without an ADD-S value
    counts as infinite (and is counted in adds_missing).
  * Contact graph precision, recall and F1 from the final maps' contact counts summed over scenes
    (null for a method that infers no contacts).
  * Physical plausibility: penetration and floating gap (mm) of the final maps, pooled.
  * Time: per-keyframe total and per stage (median, 95th percentile, maximum), real-time factor
    (summed wall time / summed recording duration), peak memory.

Writes to OUTDIR: summary.json (no NaN; null for what cannot be measured), report.md, and the
figures adds_curve.png, timing_<scene>.png and contact_graph_<scene>.png (GeoFusion on
--plot-scene, the first scene by default). Prints a short table.

Exit code: 0; 1 with --guard when GeoFusion is not ahead of FbF on mAP50:95 and on precision at
score 0.5, IoU 0.5 (or one of them is missing); 2 for bad arguments, no or unreadable evaluation
files.
"""
import argparse
import contextlib
import datetime
import glob
import io
import json
import math
import os
import platform
import re
import shlex
import subprocess
import sys

import numpy as np
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from pycocotools.coco import COCO  # noqa: E402
from pycocotools.cocoeval import COCOeval  # noqa: E402

FORMAT = 'geofusion_evaluation_v1'
METHOD_ORDER = ['FbF', 'FbF-R', 'B-SLAM', 'R-Front', 'GeoFusion']
OURS = 'GeoFusion'
BASELINE = 'FbF'
SCORE_THRESHOLD = 0.5
STAGES = ['consistency', 'association', 'lifecycle', 'stage_one', 'relations', 'stage_two']
CONTACT_COLOURS = {'P2P': 'tab:blue', 'P2C': 'tab:orange', 'C2C': 'tab:green', 'P2E': 'tab:red'}

# The paper's figures: Table I (mAP, percent) and Table II (precision / recall at score 0.5).
PAPER = {
    'FbF': {'map50': 58.4, 'map75': 28.6, 'map50_95': 30.5,
            'precision50': 0.87, 'recall50': 0.60, 'precision75': 0.56, 'recall75': 0.38},
    'B-SLAM': {'map50': 56.0, 'map75': 24.6, 'map50_95': 27.9,
               'precision50': 0.87, 'recall50': 0.27, 'precision75': 0.63, 'recall75': 0.19},
    'R-Front': {'map50': 72.3, 'map75': 50.3, 'map50_95': 45.2,
                'precision50': 0.91, 'recall50': 0.43, 'precision75': 0.75, 'recall75': 0.35},
    'GeoFusion': {'map50': 73.4, 'map75': 59.5, 'map50_95': 50.3,
                  'precision50': 0.99, 'recall50': 0.51, 'precision75': 0.91, 'recall75': 0.46},
}

REQUIRED_KEYS = [
    'map50', 'map75', 'map50_95', 'precision50', 'recall50', 'precision75', 'recall75',
    'adds_under_1cm', 'adds_under_2cm', 'adds_auc', 'contact_precision', 'contact_recall',
    'contact_f1', 'penetration_mean_mm', 'penetration_max_mm', 'float_gap_mean_mm',
    'ms_per_keyframe_p50', 'ms_per_keyframe_p95', 'realtime_factor']


class EvalError(Exception):
    """An evaluation file that cannot be used."""


# ---------------------------------------------------------------------------------------------
# Input

def load_evals(eval_dir):
    """Every DIR/<scene>/<slug>.json, sorted by scene then method order. Each dict gets '_path'
    (the file), and 'scene' defaults to the directory's name. Raises EvalError."""
    paths = sorted(glob.glob(os.path.join(eval_dir, '*', '*.json')))
    evals, seen = [], {}
    for path in paths:
        try:
            with open(path) as f:
                ev = json.load(f)
        except (OSError, ValueError) as e:
            raise EvalError('%s: %s' % (path, e))
        if not isinstance(ev, dict) or ev.get('format') != FORMAT:
            raise EvalError('%s: not a %s file' % (path, FORMAT))
        if not ev.get('method'):
            raise EvalError('%s: no method name' % path)
        ev.setdefault('scene', os.path.basename(os.path.dirname(path)))
        ev['scene'] = str(ev['scene'] or os.path.basename(os.path.dirname(path)))
        key = (ev['scene'], ev['method'])
        if key in seen:
            raise EvalError('%s: %s on %s again (also %s)' % (path, key[1], key[0], seen[key]))
        seen[key] = path
        ev['_path'] = path
        evals.append(ev)
    evals.sort(key=lambda ev: (ev['scene'], method_rank(ev['method'])))
    return evals


def method_rank(name):
    """Sort key: the paper's order, other methods after it by name."""
    return (METHOD_ORDER.index(name), '') if name in METHOD_ORDER else (len(METHOD_ORDER), name)


def by_method(evals):
    """{method: [evals sorted by scene]} in the paper's order."""
    out = {}
    for ev in sorted(evals, key=lambda ev: (method_rank(ev['method']), ev['scene'])):
        out.setdefault(ev['method'], []).append(ev)
    return out


def scenes_of(evals):
    return sorted({ev['scene'] for ev in evals})


# ---------------------------------------------------------------------------------------------
# COCO evaluation

def build_coco_inputs(evals, box_key='bbox'):
    """Pooled ground truth (a COCO dataset dict) and results (a list for loadRes), with image and
    annotation ids renumbered from 1 across the files. box_key: the ground truth's box, 'bbox'
    (projected model points) or 'mask_bbox' (visible pixels; the projected box stands in for
    ignored ground truth without one, and a file whose other ground truth has none raises
    EvalError). Also gt_origin {new annotation id:
    (file index, file's annotation id)} and det_origin [(file index, detection dict)], whose
    position p is the result id p + 1 that COCO.loadRes assigns."""
    images, annotations, results = [], [], []
    categories, gt_origin, det_origin = {}, {}, []
    for k, ev in enumerate(evals):
        where = ev.get('_path', ev.get('scene'))
        size = ev.get('image_size') or [0, 0]
        for c in ev.get('categories') or []:
            categories.setdefault(int(c['id']), {'id': int(c['id']), 'name': str(c['name'])})
        image_id = {}
        for img in ev.get('images') or []:
            if img['id'] in image_id:
                raise EvalError('%s: image %s twice' % (where, img['id']))
            image_id[img['id']] = len(images) + 1
            images.append({'id': len(images) + 1, 'width': int(size[0]), 'height': int(size[1]),
                           'file_name': '%s/%s' % (ev.get('scene'), img['id'])})
        for a in ev.get('annotations') or []:
            if a['image_id'] not in image_id:
                raise EvalError('%s: annotation %s on unknown image %s'
                                % (where, a.get('id'), a['image_id']))
            box = a.get(box_key)
            if box is None and not a.get('iscrowd'):
                raise EvalError('%s: annotation %s has no %s' % (where, a.get('id'), box_key))
            x, y, w, h = (float(v) for v in (box or a['bbox']))
            new_id = len(annotations) + 1
            annotations.append({'id': new_id, 'image_id': image_id[a['image_id']],
                                'category_id': int(a['category_id']), 'bbox': [x, y, w, h],
                                'area': float(a.get('area', w * h)) if box_key == 'bbox'
                                else w * h,
                                'iscrowd': int(a.get('iscrowd', 0))})
            gt_origin[new_id] = (k, a['id'])
        for d in ev.get('detections') or []:
            if d['image_id'] not in image_id:
                raise EvalError('%s: detection %s on unknown image %s'
                                % (where, d.get('id'), d['image_id']))
            results.append({'image_id': image_id[d['image_id']],
                            'category_id': int(d['category_id']),
                            'bbox': [float(v) for v in d['bbox']], 'score': float(d['score'])})
            det_origin.append((k, d))
    dataset = {'info': {'description': 'GeoFusion benchmark'}, 'images': images,
               'annotations': annotations,
               'categories': [categories[c] for c in sorted(categories)]}
    return dataset, results, gt_origin, det_origin


def _ratio(num, den):
    return num / den if den else None


def adds_metrics(tp_adds, gt_errors):
    """ADD-S figures from the true positives' ADD-S (metres) and one error per ground-truth
    instance (infinite when missed)."""
    tp = np.asarray(tp_adds, dtype=float)
    err = np.asarray(gt_errors, dtype=float)
    out = {'adds_tp_count': int(tp.size),
           'adds_under_1cm': float(np.mean(tp < 0.01)) if tp.size else None,
           'adds_under_2cm': float(np.mean(tp < 0.02)) if tp.size else None,
           # Area under the accuracy curve over [0, 2 cm], percent: integral of P(e < x).
           'adds_auc_2cm': (100.0 * (1.0 - float(np.mean(np.minimum(tp, 0.02))) / 0.02)
                            if tp.size else None),
           # YCB-Video: AUC of the accuracy curve up to 10 cm over every ground-truth instance.
           'adds_auc': (100.0 * (1.0 - float(np.mean(np.minimum(err, 0.1))) / 0.1)
                        if err.size else None)}
    finite = tp[np.isfinite(tp)]
    out['adds_tp_median_m'] = float(np.median(finite)) if finite.size else None
    return out


def coco_metrics(evals, score_threshold=SCORE_THRESHOLD, box_key='bbox'):
    """COCO mAP, precision / recall at the score threshold (IoU 0.5 and 0.75) and the ADD-S of
    the true positives, over the given evaluation files pooled. The list of the true positives'
    ADD-S (metres) is returned under '_adds_tp_m' (kept out of summary.json)."""
    dataset, results, gt_origin, det_origin = build_coco_inputs(evals, box_key)
    cat_ids = {c['id'] for c in dataset['categories']}
    gt = COCO()
    with contextlib.redirect_stdout(io.StringIO()):
        gt.dataset = dataset
        gt.createIndex()
    out = {'images': len(dataset['images']), 'detections': len(results),
           'ground_truth': sum(1 for a in dataset['annotations']
                               if not a['iscrowd'] and a['category_id'] in cat_ids)}
    counts = {iou: {'tp': 0, 'fp': 0, 'gt': 0} for iou in (50, 75)}
    tp_adds, missing = [], 0
    gt_errors, gt_add_errors = {}, {}
    if not results:
        # No detections: pycocotools cannot load an empty result list; nothing is found.
        value = 0.0 if out['ground_truth'] else None
        out.update(map50=value, map75=value, map50_95=value)
        for iou in counts:
            counts[iou]['gt'] = out['ground_truth']
        gt_errors = {a['id']: math.inf for a in dataset['annotations']
                     if not a['iscrowd'] and a['category_id'] in cat_ids}
    else:
        with contextlib.redirect_stdout(io.StringIO()):
            dt = gt.loadRes([dict(r) for r in results])
            coco_eval = COCOeval(gt, dt, 'bbox')
            coco_eval.evaluate()
            coco_eval.accumulate()
            coco_eval.summarize()
        stats = coco_eval.stats
        # stats are -1 where pycocotools has no ground truth to measure against.
        for key, i in (('map50_95', 0), ('map50', 1), ('map75', 2)):
            out[key] = 100.0 * float(stats[i]) if stats[i] >= 0 else None
        p = coco_eval.params
        area_all = p.areaRng[p.areaRngLbl.index('all')]
        t_index = {50: int(np.argmin(np.abs(p.iouThrs - 0.5))),
                   75: int(np.argmin(np.abs(p.iouThrs - 0.75)))}
        for e in coco_eval.evalImgs:
            if e is None or list(e['aRng']) != list(area_all) or e['maxDet'] != p.maxDets[-1]:
                continue
            gt_ignore = np.asarray(e['gtIgnore'], dtype=bool)
            for gid, ignored in zip(e['gtIds'], gt_ignore):
                if not ignored:
                    gt_errors[gid] = math.inf
                    gt_add_errors[gid] = math.inf
            for iou, t in t_index.items():
                c = counts[iou]
                c['gt'] += int(np.count_nonzero(~gt_ignore))
                for j, (did, score) in enumerate(zip(e['dtIds'], e['dtScores'])):
                    if score < score_threshold or e['dtIgnore'][t][j]:
                        continue
                    matched = int(e['dtMatches'][t][j])
                    if not matched:
                        c['fp'] += 1
                        continue
                    c['tp'] += 1
                    if iou == 50:
                        k, det = det_origin[did - 1]
                        gk, gt_file_id = gt_origin[matched]
                        assert gk == k, 'a detection matched ground truth of another file'
                        value = (det.get('adds_m') or {}).get(str(gt_file_id))
                        if value is None:
                            missing += 1
                            value = math.inf
                        tp_adds.append(float(value))
                        gt_errors[matched] = float(value)
                        add = (det.get('add_m') or {}).get(str(gt_file_id))
                        gt_add_errors[matched] = math.inf if add is None else float(add)
    for iou, c in counts.items():
        out['tp%d' % iou], out['fp%d' % iou], out['gt%d' % iou] = c['tp'], c['fp'], c['gt']
        out['precision%d' % iou] = _ratio(c['tp'], c['tp'] + c['fp'])
        out['recall%d' % iou] = _ratio(c['tp'], c['gt'])
    out.update(adds_metrics(tp_adds, list(gt_errors.values())))
    # ADD (no symmetry): the YCB-Video AUC up to 10 cm over the same ground truth, None for files
    # made before it was recorded.
    add_err = np.asarray(list(gt_add_errors.values()), dtype=float)
    has_add = any('add_m' in d for _, d in det_origin)
    out['add_auc'] = (100.0 * (1.0 - float(np.mean(np.minimum(add_err, 0.1))) / 0.1)
                      if add_err.size and has_add else None)
    out['add_under_2cm'] = (float(np.mean(add_err < 0.02)) if add_err.size and has_add else None)
    out['adds_missing'] = missing
    out['_adds_tp_m'] = tp_adds
    return out


def mask_box_metrics(evals):
    """mAP against the ground truth's instance-mask boxes (map50_mask, map75_mask,
    map50_95_mask); None when a file has no mask boxes (made before they were recorded)."""
    keys = ('map50', 'map75', 'map50_95')
    try:
        m = coco_metrics(evals, box_key='mask_bbox')
    except EvalError:
        return {k + '_mask': None for k in keys}
    return {k + '_mask': m[k] for k in keys}


# ---------------------------------------------------------------------------------------------
# BOP's metrics (Hodan et al., BOP Challenge 2020; bop_toolkit's pose_matching.py and
# calc_scores.py): MSSD and MSPD errors come in the evaluation files (bop_metrics.h, the
# appearance's symmetries); here the estimates are matched to the targets and the recalls
# averaged.

BOP_MSSD_FRACTIONS = [0.05 * k for k in range(1, 11)]   # of the object's diameter
BOP_MSPD_PIXELS = [5.0 * k for k in range(1, 11)]       # times image width / 640
BOP_VSD_THETAS = [0.05 * k for k in range(1, 11)]       # the error's thresholds; the file has
                                                        # one error per tau (5-50 % of diameter)


def _bop_match(targets, estimates, error_key, threshold, tau=None):
    """bop_toolkit's match_poses for one image and class: the estimates by score (descending,
    the top len(targets) only: the ViVo task), each matched to the unmatched target of smallest
    error below the threshold (VSD: the error at the tau-th tau). Returns the number matched."""
    matched = set()
    for det in sorted(estimates, key=lambda d: -float(d['score']))[:len(targets)]:
        errors = det.get(error_key) or {}
        best, best_error = None, threshold
        for t in targets:
            if t in matched:
                continue
            e = errors.get(str(t))
            if e is not None and tau is not None:
                e = e[tau] if len(e) > tau else None
            if e is not None and float(e) < best_error:
                best, best_error = t, float(e)
        if best is not None:
            matched.add(best)
    return len(matched)


def bop_metrics(evals):
    """AR_VSD (recall averaged over 10 taus x 10 thetas), AR_MSSD, AR_MSPD (over BOP's ten
    thresholds each) and AR, their mean, pooled and per class name; targets are the ground
    truth at least 10 % visible (not crowd). Without VSD errors in the files (evaluate_run
    --no-vsd, or files made before), AR is the mean of MSSD and MSPD and 'bop_ar_vsd' None.
    All None when a file has no BOP errors."""
    hits = {'mssd': {}, 'mspd': {}, 'vsd': {}}   # class -> [matched per threshold]
    has_vsd = all(('vsd' in d) for ev in evals for d in (ev.get('detections') or []))
    targets_per_class = {}
    for ev in evals:
        dets = ev.get('detections') or []
        if dets and 'mssd_m' not in dets[0]:
            return {'bop_ar': None, 'bop_ar_vsd': None, 'bop_ar_mssd': None, 'bop_ar_mspd': None,
                    'bop_per_class': {}}
        names = {int(c['id']): str(c['name']) for c in ev.get('categories') or []}
        diameters = {int(c['id']): c.get('diameter_m') for c in ev.get('categories') or []}
        width = float((ev.get('image_size') or [640, 480])[0]) or 640.0
        groups = {}
        for a in ev.get('annotations') or []:
            if not a.get('iscrowd'):
                groups.setdefault((a['image_id'], int(a['category_id'])), ([], []))[0].append(a['id'])
        for d in dets:
            key = (d['image_id'], int(d['category_id']))
            if key in groups:
                groups[key][1].append(d)
        for (image, cls), (targets, estimates) in groups.items():
            name = names.get(cls, str(cls))
            targets_per_class[name] = targets_per_class.get(name, 0) + len(targets)
            diameter = diameters.get(cls)
            for kind, key, thresholds in (
                    ('mssd', 'mssd_m', [f * (diameter or 0.0) for f in BOP_MSSD_FRACTIONS]),
                    ('mspd', 'mspd_px', [p * width / 640.0 for p in BOP_MSPD_PIXELS])):
                row = hits[kind].setdefault(name, [0] * len(thresholds))
                for i, th in enumerate(thresholds):
                    row[i] += _bop_match(targets, estimates, key, th)
            if has_vsd:
                row = hits['vsd'].setdefault(name, [0] * 100)
                for tau in range(10):
                    for i, th in enumerate(BOP_VSD_THETAS):
                        row[10 * tau + i] += _bop_match(targets, estimates, 'vsd', th, tau)
    total = sum(targets_per_class.values())
    if not total:
        return {'bop_ar': None, 'bop_ar_vsd': None, 'bop_ar_mssd': None, 'bop_ar_mspd': None,
                'bop_per_class': {}}

    def ar(kind, names):
        n = sum(targets_per_class[c] for c in names)
        if not n or (kind == 'vsd' and not has_vsd):
            return None
        count = 100 if kind == 'vsd' else 10
        per_threshold = [sum(hits[kind].get(c, [0] * count)[i] for c in names) / n
                         for i in range(count)]
        return float(np.mean(per_threshold))

    out = {'bop_ar_' + k: ar(k, targets_per_class) for k in ('vsd', 'mssd', 'mspd')}
    parts = [out[k] for k in ('bop_ar_vsd', 'bop_ar_mssd', 'bop_ar_mspd') if out[k] is not None]
    out['bop_ar'] = float(np.mean(parts))
    out['bop_per_class'] = {c: {'targets': targets_per_class[c], 'ar_vsd': ar('vsd', [c]),
                                'ar_mssd': ar('mssd', [c]), 'ar_mspd': ar('mspd', [c])}
                            for c in sorted(targets_per_class)}
    return out


# ---------------------------------------------------------------------------------------------
# The other measures

def contact_metrics(evals):
    """Contact graph precision / recall / F1 from final_map.contacts summed over the files; all
    null when no file has contacts."""
    keys = ('true', 'estimated', 'correct', 'true_pairs', 'estimated_pairs', 'correct_pairs')
    sums, any_contacts = {k: 0 for k in keys}, False
    for ev in evals:
        c = (ev.get('final_map') or {}).get('contacts')
        if c is None:
            continue
        any_contacts = True
        for key in sums:
            sums[key] += int(c.get(key) or 0)
    out = {}
    for suffix, (true, estimated, correct) in (('', ('true', 'estimated', 'correct')),
                                               ('_pair', ('true_pairs', 'estimated_pairs',
                                                          'correct_pairs'))):
        if not any_contacts:
            precision = recall = f1 = None
        else:
            precision = _ratio(sums[correct], sums[estimated])
            recall = _ratio(sums[correct], sums[true])
            if precision is None or recall is None:
                f1 = None
            else:
                f1 = (2 * precision * recall / (precision + recall) if precision + recall > 0
                      else 0.0)
        out.update({'contact%s_precision' % suffix: precision,
                    'contact%s_recall' % suffix: recall, 'contact%s_f1' % suffix: f1})
    for key in ('true', 'estimated', 'correct'):
        out['contact_' + key] = sums[key] if any_contacts else None
    out.update(contact_kind_metrics(evals))
    return out


CONTACT_KINDS = ('support', 'leaning', 'side')


def contact_kind_metrics(evals):
    """Precision / recall / F1 of every contact per kind (support, leaning, side), as (object
    pair, kind), from final_map.contacts.by_kind summed over the files: contact_<kind>_precision
    ... and contact_<kind>_true / _estimated / _correct; null without contacts."""
    sums = {k: {'true': 0, 'estimated': 0, 'correct': 0} for k in CONTACT_KINDS}
    any_contacts = False
    for ev in evals:
        by_kind = ((ev.get('final_map') or {}).get('contacts') or {}).get('by_kind')
        if by_kind is None:
            continue
        any_contacts = True
        for kind in CONTACT_KINDS:
            for key in sums[kind]:
                sums[kind][key] += int((by_kind.get(kind) or {}).get(key) or 0)
    out = {}
    for kind in CONTACT_KINDS:
        s = sums[kind]
        precision = _ratio(s['correct'], s['estimated']) if any_contacts else None
        recall = _ratio(s['correct'], s['true']) if any_contacts else None
        f1 = None
        if precision is not None and recall is not None:
            f1 = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
        prefix = 'contact_%s_' % kind
        out.update({prefix + 'precision': precision, prefix + 'recall': recall,
                    prefix + 'f1': f1})
        for key in s:
            out[prefix + key] = s[key] if any_contacts else None
    return out


def _pooled(evals, key):
    values = []
    for ev in evals:
        values.extend(float(v) for v in (ev.get('final_map') or {}).get(key) or []
                      if v is not None)
    return np.asarray(values, dtype=float)


def physics_metrics(evals):
    """Penetration and floating gap (mm) of the final maps, pooled; 0 for no values."""
    pen, gap = _pooled(evals, 'penetration_mm'), _pooled(evals, 'gap_mm')
    return {'penetration_mean_mm': float(pen.mean()) if pen.size else 0.0,
            'penetration_max_mm': float(pen.max()) if pen.size else 0.0,
            'float_gap_mean_mm': float(gap.mean()) if gap.size else 0.0,
            'float_gap_max_mm': float(gap.max()) if gap.size else 0.0,
            'physics_pairs': int(pen.size)}


def plan_metrics(evals):
    """The support graph as a plan (evaluation's 'scene_graph'): unsafe removal steps per scene
    (a true object taken while a true object the map has still rests or leans on it), the steps
    under objects the map missed, and the precision of "free to pick". None where no file has
    it."""
    blocks = [(ev.get('scene'), ev['scene_graph']) for ev in evals if ev.get('scene_graph')]
    if not blocks:
        return {'plan_scenes': None}
    predicted = sum(b['free_to_pick']['predicted'] for _, b in blocks)
    correct = sum(b['free_to_pick']['correct'] for _, b in blocks)
    unsafe = [b['unsafe_steps'] for _, b in blocks]
    first = next(('%s: %s' % (scene, b['first_unsafe_step']) for scene, b in blocks
                  if b['first_unsafe_step']), None)
    return {'plan_scenes': len(blocks),
            'plan_steps': sum(b['true_steps'] for _, b in blocks),
            'plan_unsafe_steps': int(sum(unsafe)),
            'plan_unsafe_per_scene': float(np.mean(unsafe)),
            'plan_unsafe_max_scene': int(max(unsafe)),
            'plan_steps_under_missed': sum(b['steps_under_missed_objects'] for _, b in blocks),
            # Files written before the physics check have no figure: None.
            'plan_unsafe_in_physics': (
                sum(b['unsafe_steps_in_physics'] for _, b in blocks)
                if all('unsafe_steps_in_physics' in b for _, b in blocks) else None),
            'plan_first_unsafe': first,
            'free_predicted': predicted,
            'free_correct': correct,
            'free_precision': _ratio(correct, predicted),
            'free_true': sum(b['free_to_pick']['true'] for _, b in blocks)}


def stability_metrics(evals):
    """Physical stability (Bullet, evaluation's 'stability'): the share of the final maps' true
    objects that stay put, the checked objects' motion, the least stable pair, and the ground
    truth's share on the same settings (the reference row). None where no file has it."""
    blocks = [(ev.get('scene'), ev['stability']) for ev in evals if ev.get('stability')]
    if not blocks:
        return {'stability_true_share': None, 'stability_truth_share': None}
    true_n = sum(b['true_objects'] for _, b in blocks)
    stable = sum(b['true_stable'] for _, b in blocks)
    moves = [body['translation_mm'] for _, b in blocks for body in b['map']['bodies']
             if body['simulated'] and not body['interpenetrating']]
    turns = [body['rotation_deg'] for _, b in blocks for body in b['map']['bodies']
             if body['simulated'] and not body['interpenetrating']]
    truth_n = sum(len(b['ground_truth']['bodies']) for _, b in blocks)
    truth_stable = sum(b['ground_truth']['stable'] for _, b in blocks)
    worst = max(blocks, key=lambda sb: sb[1]['map']['least_stable_pair_mm'])
    return {'stability_true_objects': true_n,
            'stability_true_stable': stable,
            'stability_true_share': _ratio(stable, true_n),
            'stability_true_interpenetrating': sum(b['true_interpenetrating'] for _, b in blocks),
            'stability_mean_translation_mm': float(np.mean(moves)) if moves else 0.0,
            'stability_max_translation_mm': float(np.max(moves)) if moves else 0.0,
            'stability_max_rotation_deg': float(np.max(turns)) if turns else 0.0,
            'stability_least_stable_pair': ('%s: %s (%.1f mm)' % (
                worst[0], worst[1]['least_stable_pair'], worst[1]['map']['least_stable_pair_mm'])
                if worst[1]['least_stable_pair'] else None),
            'stability_truth_objects': truth_n,
            'stability_truth_stable': truth_stable,
            'stability_truth_share': _ratio(truth_stable, truth_n),
            'stability_settings': blocks[0][1]['settings']}


def _percentile(values, q):
    return float(np.percentile(values, q)) if len(values) else None


def timing_metrics(evals):
    """Per-keyframe time (total and per stage), real-time factor and peak memory."""
    def pooled(stage):
        return np.asarray([float(v) for ev in evals
                           for v in (ev.get('timings_ms') or {}).get(stage) or []], dtype=float)
    total = pooled('total')
    out = {'keyframes': int(total.size),
           'ms_per_keyframe_mean': float(total.mean()) if total.size else None,
           'ms_per_keyframe_p50': _percentile(total, 50),
           'ms_per_keyframe_p95': _percentile(total, 95),
           'ms_per_keyframe_max': float(total.max()) if total.size else None}
    for stage in STAGES:
        values = pooled(stage)
        out['ms_%s_p50' % stage] = _percentile(values, 50)
        out['ms_%s_p95' % stage] = _percentile(values, 95)
    wall = [ev.get('wall_time_s') for ev in evals]
    duration = [ev.get('recording_duration_s') for ev in evals]
    if any(v is None for v in wall + duration):
        out['wall_time_s'] = out['recording_duration_s'] = out['realtime_factor'] = None
    else:
        out['wall_time_s'] = float(sum(wall))
        out['recording_duration_s'] = float(sum(duration))
        out['realtime_factor'] = _ratio(out['wall_time_s'], out['recording_duration_s'])
    rss = [float(ev['peak_rss_mb']) for ev in evals if ev.get('peak_rss_mb') is not None]
    out['peak_rss_mb'] = max(rss) if rss else None
    return out


def final_map_figures(evals):
    """Objects in the final maps, matched ones, true ones (summed) and their ADD-S."""
    fm = [ev.get('final_map') or {} for ev in evals]
    adds = _pooled(evals, 'adds_m')
    finite = adds[np.isfinite(adds)]
    return {'final_objects': sum(int(m.get('objects') or 0) for m in fm),
            'final_matched': sum(int(m.get('matched') or 0) for m in fm),
            'final_true_objects': sum(int(m.get('true_objects') or 0) for m in fm),
            'final_adds_mean_m': float(finite.mean()) if finite.size else None,
            'final_adds_under_1cm': float(np.mean(adds < 0.01)) if adds.size else None}


def lifecycle_figures(evals):
    """Object lifecycle summed over the scenes: lost well-seen objects, flip-flops (None for a
    method without a persistent map)."""
    lc = [ev.get('lifecycle') for ev in evals]
    if not lc or any(x is None for x in lc):
        return {'lifecycle_lost': None, 'lifecycle_flip_flops': None, 'lifecycle_objects': None,
                'removals': None, 'removal_ghosts': None, 'removal_latency_max': None,
                'removal_latency_mean': None}
    # Changed scenes: objects taken away (or moved: the old place), keyframes until the map let
    # them go, and those it kept (ghosts).
    latencies = [int(v) for x in lc for v in x.get('removal_latencies') or []]
    removals = sum(int(x.get('removals') or 0) for x in lc)
    return {'lifecycle_lost': sum(int(x.get('lost') or 0) for x in lc),
            'lifecycle_flip_flops': sum(int(x.get('flip_flops') or 0) for x in lc),
            'lifecycle_objects': sum(len(x.get('objects') or []) for x in lc),
            'removals': removals,
            'removal_ghosts': sum(int(x.get('ghosts') or 0) for x in lc),
            'removal_latency_max': max(latencies) if latencies else None,
            'removal_latency_mean': float(np.mean(latencies)) if latencies else None}


def class_recall(evals):
    """Per class, over the scenes: {class: [true objects, of them in the final map]} (from the
    evaluation files' contact_graph objects and their matches)."""
    out = {}
    for ev in evals:
        graph = ev.get('contact_graph') or {}
        matched = {int(o['match']) for o in graph.get('estimated_objects') or []
                   if o.get('match', -1) is not None and int(o.get('match', -1)) >= 0}
        for o in graph.get('true_objects') or []:
            counts = out.setdefault(str(o['class_name']), [0, 0])
            counts[0] += 1
            counts[1] += int(o['index']) in matched
    return out


def detector_error_figures(evals):
    """The detector's persistent phantoms and swapped classes, and how many of them the final
    maps keep, summed over the scenes (None for files made before they were measured)."""
    fm = [ev.get('final_map') or {} for ev in evals]
    out = {}
    for key in ('persistent_phantoms', 'surviving_phantoms', 'persistent_swaps',
                'surviving_swaps', 'class_changes', 'classes_kept'):
        values = [m.get(key) for m in fm]
        out[key] = None if any(v is None for v in values) else sum(int(v) for v in values)
    return out


def trajectory_figures(evals):
    """Camera trajectory error (ATE RMSE, mm) of the method and of the odometry it was given,
    mean over the scenes."""
    tr = [ev.get('trajectory') or {} for ev in evals]
    out = {}
    for key, name in (('ate_rmse_m', 'ate_mm'), ('odometry_ate_rmse_m', 'odometry_ate_mm')):
        values = [t.get(key) for t in tr]
        out[name] = (None if not values or any(v is None for v in values)
                     else 1000.0 * float(np.mean(values)))
    return out


def method_summary(evals):
    """Every measure for one method's evaluation files (one or more scenes)."""
    out = {'method': evals[0]['method'] if evals else None, 'scenes': len(evals)}
    out.update(coco_metrics(evals))
    out.update(mask_box_metrics(evals))
    out.update(bop_metrics(evals))
    out.update(detector_error_figures(evals))
    out.update(trajectory_figures(evals))
    out['class_recall'] = class_recall(evals)
    out.update(contact_metrics(evals))
    out.update(physics_metrics(evals))
    out.update(stability_metrics(evals))
    out.update(plan_metrics(evals))
    out.update(timing_metrics(evals))
    out.update(final_map_figures(evals))
    out.update(lifecycle_figures(evals))
    return out


# ---------------------------------------------------------------------------------------------
# Summary, targets, guard

def machine_info():
    """uname -srm, CPU model and core count."""
    cpu = None
    try:
        with open('/proc/cpuinfo') as f:
            for line in f:
                if line.startswith('model name'):
                    cpu = line.split(':', 1)[1].strip()
                    break
    except OSError:
        pass
    return {'uname': '%s %s %s' % (platform.system(), platform.release(), platform.machine()),
            'cpu': cpu or platform.processor() or 'unknown', 'cores': os.cpu_count()}


def git_commit():
    """Short commit of the repository holding this script, or 'unknown'."""
    try:
        out = subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], capture_output=True,
                             text=True, timeout=10,
                             cwd=os.path.dirname(os.path.abspath(__file__)))
        return out.stdout.strip() or 'unknown'
    except (OSError, subprocess.SubprocessError):
        return 'unknown'


def summarize(evals, suite=None, commit=None):
    """summary.json's content (still with the in-memory '_' keys)."""
    methods = {name: method_summary(group) for name, group in by_method(evals).items()}
    scenes = {}
    for scene in scenes_of(evals):
        group = by_method([ev for ev in evals if ev['scene'] == scene])
        scenes[scene] = {name: method_summary(g) for name, g in group.items()}
    summary = {'suite': suite, 'date': datetime.datetime.now().astimezone()
               .isoformat(timespec='seconds'),
               'commit': commit, 'machine': machine_info(), 'methods': methods,
               'scenes': scenes}
    summary['targets'] = check_targets(methods, suite)
    for name, m in methods.items():
        if name not in summary:
            summary[name] = m
    return summary


def json_ready(obj):
    """Plain JSON types; NaN and infinities become null; keys starting with '_' are dropped."""
    if isinstance(obj, dict):
        return {str(k): json_ready(v) for k, v in obj.items() if not str(k).startswith('_')}
    if isinstance(obj, (list, tuple)):
        return [json_ready(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    return obj


def _ahead(methods, key):
    """(ours, best other value, its name) for 'GeoFusion ahead of every other method'."""
    others = [(m.get(key), name) for name, m in methods.items()
              if name != OURS and m.get(key) is not None]
    best = max(others) if others else (None, None)
    return (methods.get(OURS) or {}).get(key), best[0], best[1]


# Suites whose detector errs persistently (docs/dataset.md) and the targets set on them
# (docs/BENCHMARK.md); the other suites keep the paper-reproduction targets.
PERSISTENT_SUITES = ('bench', 'bench_rgb')


def check_targets(methods, suite=None):
    """The targets of the suite: [{'target', 'measured', 'met', 'status'}]."""
    ours = methods.get(OURS) or {}
    rows = []

    def add(target, measured, met, missed_by):
        status = 'met' if met else ('missed by %s' % missed_by if missed_by else 'missed')
        rows.append({'target': target, 'measured': measured, 'met': bool(met),
                     'status': status})

    for key, label, fmt, unit in (('map75', 'mAP75', '%.1f', ' points'),
                                  ('map50_95', 'mAP50:95', '%.1f', ' points'),
                                  ('precision50', 'precision (IoU 0.5, score 0.5)', '%.3f', '')):
        value, best, best_name = _ahead(methods, key)
        target = '%s: %s ahead of every other method' % (label, OURS)
        if value is None or best is None:
            add(target, 'n/a', False, 'n/a (%s)' % ('not measured' if value is None
                                                     else 'no other method'))
            continue
        measured = (fmt + ' vs ' + fmt + ' (%s)') % (value, best, best_name)
        add(target, measured, value > best,
            (fmt % (best - value)) + unit + (' (tie)' if value == best else ''))
    if suite in PERSISTENT_SUITES:
        _persistent_suite_targets(methods, add, suite)
    else:
        _paper_suite_targets(methods, add)
    _stability_targets(methods, add, suite)
    _plan_targets(methods, add, suite)
    return rows


def _plan_targets(methods, add, suite=None):
    """Issue 50: no unsafe removal step for true objects on bench and bench_rgb."""
    ours = methods.get(OURS) or {}
    if ours.get('plan_scenes') is None or suite not in PERSISTENT_SUITES:
        return
    add('plan: %s 0 unsafe removal steps of true objects' % OURS,
        '%d in %d scenes (max %d in one; %s of them disturb another object in physics)'
        % (ours['plan_unsafe_steps'], ours['plan_scenes'], ours['plan_unsafe_max_scene'],
           _int(ours.get("plan_unsafe_in_physics"))),
        ours['plan_unsafe_steps'] == 0, '%d steps' % ours['plan_unsafe_steps'])


def _stability_targets(methods, add, suite=None):
    """Issue 50: the ground truth at least 99 % stable on every suite; GeoFusion at least 95 % on
    bench, bench_rgb and the real frames, ahead of every other method."""
    ours = methods.get(OURS) or {}
    truth = next((m.get('stability_truth_share') for m in methods.values()
                  if m.get('stability_truth_share') is not None), None)
    if truth is None:
        return  # evaluations from before the stability check
    add('stability: ground truth >= 0.99 stable', '%.3f' % truth, truth >= 0.99,
        '%.3f' % (0.99 - truth))
    value, best, best_name = _ahead(methods, 'stability_true_share')
    if suite in PERSISTENT_SUITES + ('real',):
        add('stability: %s >= 0.95 of its true objects stable' % OURS,
            'n/a' if value is None else '%.3f' % value, value is not None and value >= 0.95,
            'n/a' if value is None else '%.3f' % (0.95 - value))
    if value is not None and best is not None:
        add('stability: %s ahead of every other method' % OURS,
            '%.3f vs %.3f (%s)' % (value, best, best_name), value > best, '%.3f' % (best - value))


# Issue 20: contact F1 per kind on the persistent-error suites.
CONTACT_F1_TARGETS = {'bench': 0.9, 'bench_rgb': 0.8}


def _persistent_suite_targets(methods, add, suite=None):
    """Per-keyframe ADD-S AUC 10 points above FbF; no lost object; no phantom or swapped class
    in the final maps."""
    ours = methods.get(OURS) or {}
    auc, fbf_auc = ours.get('adds_auc'), (methods.get(BASELINE) or {}).get('adds_auc')
    target = 'per-keyframe ADD-S AUC: %s >= %s + 10 points' % (OURS, BASELINE)
    if auc is None or fbf_auc is None:
        add(target, 'n/a', False, 'n/a (not measured)')
    else:
        add(target, '%.1f vs %.1f' % (auc, fbf_auc), auc >= fbf_auc + 10.0,
            '%.1f points' % (fbf_auc + 10.0 - auc))
    lost = ours.get('lifecycle_lost')
    target = 'lost objects: %s none' % OURS
    if lost is None:
        add(target, 'n/a', False, 'n/a (not measured)')
    else:
        add(target, '%d of %s' % (lost, ours.get('lifecycle_objects')), lost == 0,
            '%d objects' % lost)
    bound = CONTACT_F1_TARGETS.get(suite, 0.9)
    for kind in CONTACT_KINDS:
        f1 = ours.get('contact_%s_f1' % kind)
        target = 'contact F1, %s: %s >= %.2f' % (kind, OURS, bound)
        if f1 is None:
            add(target, 'n/a (%s true contacts)' % ours.get('contact_%s_true' % kind), False,
                'n/a (not measured)')
        else:
            add(target, '%.3f' % f1, f1 >= bound, '%.3f' % (bound - f1))
    if ours.get('removals'):
        latency, ghosts = ours.get('removal_latency_max'), ours.get('removal_ghosts')
        target = 'changed scenes: %s lets every object taken away go within 5 keyframes' % OURS
        measured = '%d removals, %d ghosts, latency max %s keyframes' % (
            ours['removals'], ghosts, 'n/a' if latency is None else latency)
        add(target, measured, ghosts == 0 and latency is not None and latency <= 5,
            '%d ghosts' % ghosts if ghosts else '%s keyframes' % (
                'n/a' if latency is None else latency - 5))
    phantoms, swaps = ours.get('surviving_phantoms'), ours.get('surviving_swaps')
    target = 'persistent phantoms and swapped classes in the final maps: %s none' % OURS
    if phantoms is None or swaps is None:
        add(target, 'n/a', False, 'n/a (not measured)')
    else:
        add(target, '%d of %s phantoms, %d of %s swaps' % (
            phantoms, ours.get('persistent_phantoms'), swaps, ours.get('persistent_swaps')),
            phantoms + swaps == 0, '%d objects' % (phantoms + swaps))


def _paper_suite_targets(methods, add):
    """The paper-reproduction targets (independent errors): 1.6 x FbF on mAP50:95, precision,
    ADD-S, contacts, plausibility and time."""
    ours = methods.get(OURS) or {}
    ours_map, fbf_map = ours.get('map50_95'), (methods.get(BASELINE) or {}).get('map50_95')
    target = 'mAP50:95: %s >= 1.6 x %s' % (OURS, BASELINE)
    if ours_map is None or fbf_map is None:
        add(target, 'n/a', False, 'n/a (not measured)')
    elif fbf_map <= 0:
        add(target, '%.1f vs %.1f' % (ours_map, fbf_map), ours_map >= 0, None)
    else:
        ratio = ours_map / fbf_map
        add(target, '%.2f x (%.1f vs %.1f)' % (ratio, ours_map, fbf_map), ratio >= 1.6,
            '%.2f x' % (1.6 - ratio))

    for key, label, op, bound, fmt, unit in (
            ('precision50', 'precision (IoU 0.5, score 0.5)', '>=', 0.97, '%.3f', ''),
            ('adds_under_1cm', 'ADD-S < 1 cm share', '>=', 0.90, '%.3f', ''),
            ('contact_f1', 'contact F1', '>=', 0.85, '%.3f', ''),
            ('penetration_mean_mm', 'mean penetration', '<', 2.0, '%.2f', ' mm'),
            ('ms_per_keyframe_p95', 'time per keyframe, p95', '<', 50.0, '%.1f', ' ms'),
            ('realtime_factor', 'real-time factor', '<', 0.2, '%.3f', '')):
        target = '%s: %s %s %s%s' % (label, OURS, op, fmt % bound, unit)
        value = ours.get(key)
        if value is None:
            add(target, 'n/a', False, 'n/a (not measured)')
            continue
        met = value >= bound if op == '>=' else value < bound
        add(target, (fmt % value) + unit, met, (fmt % abs(value - bound)) + unit)


def guard(methods):
    """(passed, message): GeoFusion ahead of FbF on mAP50:95 and precision50."""
    ours, fbf = methods.get(OURS), methods.get(BASELINE)
    if ours is None or fbf is None:
        return False, 'guard: cannot compare, %s missing' % (OURS if ours is None else BASELINE)
    problems = []
    for key, label in (('map50_95', 'mAP50:95'), ('precision50', 'precision50')):
        a, b = ours.get(key), fbf.get(key)
        if a is None:
            problems.append('%s of %s not measured' % (label, OURS))
        elif b is not None and not a > b:
            problems.append('%s %s %s <= %s %s' % (label, OURS, _num(a, 3), BASELINE, _num(b, 3)))
    if problems:
        return False, 'guard failed: ' + '; '.join(problems)
    return True, 'guard passed: %s ahead of %s on mAP50:95 and precision50' % (OURS, BASELINE)


# ---------------------------------------------------------------------------------------------
# Figures

def adds_curve(tp_adds, x_max=0.02, n=201):
    """(x in metres, share of true positives with ADD-S < x)."""
    x = np.linspace(0.0, x_max, n)
    tp = np.sort(np.asarray(tp_adds, dtype=float))
    if not tp.size:
        return x, np.zeros_like(x)
    return x, np.searchsorted(tp, x, side='left') / tp.size


def plot_adds_curve(methods, path):
    """ADD-S accuracy-threshold curve over [0, 2 cm] for the methods with true positives."""
    fig, ax = plt.subplots(figsize=(5.5, 4.0))
    drawn = 0
    for name, m in methods.items():
        tp = m.get('_adds_tp_m') or []
        if not tp:
            continue
        x, y = adds_curve(tp)
        ax.plot(100.0 * x, y, lw=2, label='%s (AUC %.1f, n=%d)' % (name, m['adds_auc_2cm'],
                                                                   len(tp)))
        drawn += 1
    ax.set_xlim(0, 2)
    ax.set_ylim(0, 1.02)
    ax.set_xlabel('ADD-S threshold (cm)')
    ax.set_ylabel('accuracy (share of true positives)')
    ax.set_title('Pose accuracy of true positives (IoU 0.5, score 0.5)')
    ax.grid(True, alpha=0.3)
    if drawn:
        ax.legend(loc='lower right', fontsize=8, title='AUC over [0, 2 cm]', title_fontsize=8)
    else:
        ax.text(1, 0.5, 'no true positives', ha='center')
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_timing(ev, path):
    """Per-keyframe run time by stage (stacked) of one evaluation file."""
    t = ev.get('timings_ms') or {}
    series = [np.asarray(t.get(s) or [], dtype=float) for s in STAGES]
    n = max([len(s) for s in series] + [len(t.get('total') or [])])
    series = [np.pad(s, (0, n - len(s))) for s in series]
    x = np.arange(n)
    fig, ax = plt.subplots(figsize=(7.0, 3.6))
    if n:
        ax.stackplot(x, *series, labels=[s.replace('_', ' ') for s in STAGES], alpha=0.85)
        total = np.asarray(t.get('total') or [], dtype=float)
        if total.size:
            ax.plot(np.arange(total.size), total, color='k', lw=0.8, label='total')
        ax.set_xlim(0, max(n - 1, 1))
        top = max(float(np.max(np.sum(series, axis=0))), float(total.max()) if total.size
                  else 0.0)
        ax.set_ylim(0, 1.3 * top if top > 0 else 1.0)  # room for the legend
        ax.legend(loc='upper left', fontsize=7, ncol=6)
    else:
        ax.set_ylim(0, 1.0)
    ax.set_xlabel('keyframe')
    ax.set_ylabel('time (ms)')
    ax.set_title('%s on %s: time per keyframe by stage' % (ev['method'], ev['scene']))
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def short_name(class_name):
    """'003_cracker_box' -> 'cracker_box'."""
    return re.sub(r'^\d+_', '', str(class_name))


def _draw_graph(ax, objects, contacts, title, estimated):
    """Top view of objects (key -> dict with xy, z, class_name) and their contacts. Table
    contacts are rings around the object; contacts with an object directly underneath (top-view
    distance under 1 cm) are diamonds around the upper one; incorrect estimated contacts
    dashed."""
    for o in objects.values():
        x, y = o['xy']
        unmatched = estimated and o.get('match', 0) < 0
        ax.plot(x, y, 'x' if unmatched else 'o', color='tab:red' if unmatched else 'k', ms=5,
                zorder=3)
    # labels, nudged up for objects close in the top view
    placed = []
    for o in sorted(objects.values(), key=lambda o: o.get('z', 0.0)):
        x, y = o['xy']
        k = sum(1 for (px, py) in placed if math.hypot(px - x, py - y) < 0.03)
        placed.append((x, y))
        ax.annotate(short_name(o.get('class_name', '')), (x, y), xytext=(4, 4 + 8 * k),
                    textcoords='offset points', fontsize=6)
    skipped = 0
    for c in contacts:
        colour = CONTACT_COLOURS.get(c.get('type'), 'tab:gray')
        style = '--' if estimated and c.get('correct') is False else '-'
        a, b = c.get('a'), c.get('b')
        if a == -1 or b == -1:
            other = objects.get(b if a == -1 else a)
            if other is None:
                skipped += 1
                continue
            ax.scatter([other['xy'][0]], [other['xy'][1]], s=220, facecolors='none',
                       edgecolors=colour, linewidths=1.5, linestyle=style, zorder=2)
            continue
        oa, ob = objects.get(a), objects.get(b)
        if oa is None or ob is None:
            skipped += 1
            continue
        (xa, ya), (xb, yb) = oa['xy'], ob['xy']
        if math.hypot(xa - xb, ya - yb) < 0.01:
            upper = oa if oa.get('z', 0.0) >= ob.get('z', 0.0) else ob
            ax.scatter([upper['xy'][0]], [upper['xy'][1]], s=120, marker='D',
                       facecolors='none', edgecolors=colour, linewidths=1.5, linestyle=style,
                       zorder=2)
        else:
            ax.plot([xa, xb], [ya, yb], color=colour, ls=style, lw=1.8, zorder=1)
    ax.set_title(title + (' (%d contacts of unknown objects)' % skipped if skipped else ''),
                 fontsize=9)
    ax.set_xlabel('x (m)')
    ax.set_ylabel('y (m)')
    ax.grid(True, alpha=0.3)


def plot_contact_graph(ev, path):
    """True and estimated contact graphs (top view) of one evaluation file."""
    g = ev.get('contact_graph') or {}
    truth = {o['index']: o for o in g.get('true_objects') or []}
    est = {o['id']: o for o in g.get('estimated_objects') or []}
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 5.0))
    _draw_graph(axes[0], truth, g.get('true_contacts') or [], 'ground truth (%d objects, %d '
                'contacts)' % (len(truth), len(g.get('true_contacts') or [])), False)
    _draw_graph(axes[1], est, g.get('estimated_contacts') or [], '%s (%d objects, %d contacts)'
                % (ev['method'], len(est), len(g.get('estimated_contacts') or [])), True)
    # the same metric frame in both panels
    xy = np.asarray([o['xy'] for o in list(truth.values()) + list(est.values())] or [[0, 0]],
                    dtype=float)
    centre = (xy.min(axis=0) + xy.max(axis=0)) / 2
    half = max(float((xy.max(axis=0) - xy.min(axis=0)).max()) / 2 + 0.05, 0.1)
    for ax in axes:
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_aspect('equal', adjustable='box')
    handles = [Line2D([], [], color=c, lw=2, label=t) for t, c in CONTACT_COLOURS.items()]
    handles += [Line2D([], [], color='k', lw=1.5, ls='--', label='incorrect (estimate)'),
                Line2D([], [], marker='o', mfc='none', mec='k', ls='', ms=11,
                       label='on the table'),
                Line2D([], [], marker='D', mfc='none', mec='k', ls='', ms=8,
                       label='on the object below'),
                Line2D([], [], marker='x', color='tab:red', ls='', label='unmatched estimate')]
    fig.legend(handles=handles, loc='lower center', ncol=len(handles), fontsize=8)
    fig.suptitle('Contact graph, %s (top view)' % ev['scene'])
    fig.tight_layout(rect=(0, 0.06, 1, 0.96))
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_figures(evals, summary, out_dir, plot_scene):
    """The three figures; returns {name: file name} of those written."""
    figures = {}
    path = os.path.join(out_dir, 'adds_curve.png')
    plot_adds_curve(summary['methods'], path)
    figures['adds_curve'] = os.path.basename(path)
    ours = [ev for ev in evals if ev['method'] == OURS and ev['scene'] == plot_scene]
    if not ours:
        print('bench_report: no %s evaluation on %s, no timing and contact graph figures'
              % (OURS, plot_scene), file=sys.stderr)
        return figures
    safe = re.sub(r'[^A-Za-z0-9_.-]', '_', plot_scene)
    path = os.path.join(out_dir, 'timing_%s.png' % safe)
    plot_timing(ours[0], path)
    figures['timing'] = os.path.basename(path)
    path = os.path.join(out_dir, 'contact_graph_%s.png' % safe)
    plot_contact_graph(ours[0], path)
    figures['contact_graph'] = os.path.basename(path)
    return figures


# ---------------------------------------------------------------------------------------------
# Report

def _num(value, digits=1, unit=''):
    """A number with the given decimals, 'n/a' for None / NaN."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return 'n/a'
    return ('%.*f' % (digits, value)) + unit


def _int(value):
    return 'n/a' if value is None else str(int(value))


def _table(header, rows, numeric=True):
    """A markdown table; numeric: columns after the first right-aligned."""
    lines = ['| ' + ' | '.join(header) + ' |',
             '|' + '|'.join(['---'] + ['---:' if numeric else '---'] * (len(header) - 1))
             + '|']
    lines += ['| ' + ' | '.join(str(c) for c in row) + ' |' for row in rows]
    return lines


def stability_section(methods):
    """The stability table: every method's final map under gravity, the ground truth below."""
    have = [(n, m) for n, m in methods.items() if m.get('stability_true_share') is not None]
    if not have:
        return []
    c = have[0][1]['stability_settings']
    md = ['## Stability (Bullet, %.1f s of gravity)' % c['duration_s'], '',
          'Each final map on its support plane as the objects\' %s (density %g kg/m^3, '
          'friction %g); stable: moves under %g mm and %g deg. Objects that start more than %g mm '
          'into another or the table are counted apart (not stable).' % (
              'convex parts' if c.get('convex_parts') else 'convex hulls',
              c['density_kg_m3'], c['friction'], 1000 * c['stable_translation_m'],
              c['stable_rotation_deg'], 1000 * c['start_penetration_m']), '']
    rows = [[n, '%d / %d' % (m['stability_true_stable'], m['stability_true_objects']),
             _num(m['stability_true_share'], 3), str(m['stability_true_interpenetrating']),
             _num(m['stability_mean_translation_mm'], 1), _num(m['stability_max_translation_mm'], 1),
             _num(m['stability_max_rotation_deg'], 1), m['stability_least_stable_pair'] or '-']
            for n, m in have]
    t = have[0][1]
    rows.append(['ground truth', '%d / %d' % (t['stability_truth_stable'], t['stability_truth_objects']),
                 _num(t['stability_truth_share'], 3), '-', '-', '-', '-', '-'])
    return md + _table(['method', 'true objects stable', 'share', 'start interpenetrating',
                   'motion mean (mm)', 'motion max (mm)', 'turn max (deg)', 'least stable pair'],
                  rows) + ['']


def plan_section(methods):
    """The plan table: every method's removal order against the true support graph."""
    have = [(n, m) for n, m in methods.items() if m.get('plan_scenes') is not None]
    if not have:
        return []
    md = ['## The support graph as a plan', '',
          'Each final map\'s removal order (top first, docs/scene_graph.md) against the true '
          'support graph: a step is unsafe when it takes a true object while a true object the '
          'map also has still rests or leans on it; steps under objects the map missed are '
          'counted apart. "In physics": the unsafe steps after which another true object moves '
          'over the stability bounds (the true objects left, with and without the one taken, '
          'under gravity); the others rest on a true contact whose objects do not bear on each '
          'other. "Free to pick": the map\'s true objects it calls free, and of them free '
          'in the truth. A method without contacts calls every object free.', '']
    rows = [[n, str(m['plan_steps']), str(m['plan_unsafe_steps']),
             _int(m.get("plan_unsafe_in_physics")),
             _num(m['plan_unsafe_per_scene'], 2), str(m['plan_steps_under_missed']),
             '%d / %d' % (m['free_correct'], m['free_predicted']), _num(m['free_precision'], 3),
             m['plan_first_unsafe'] or '-'] for n, m in have]
    return md + _table(['method', 'steps (true objects)', 'unsafe', 'unsafe in physics',
                        'unsafe per scene',
                   'under a missed object', 'free right / called free', 'free precision',
                   'first unsafe step'], rows) + ['']


def write_report(summary, out_dir, figures, command):
    """report.md from the summary."""
    methods, scenes = summary['methods'], summary['scenes']
    machine = summary['machine']
    n_keyframes = {name: m.get('keyframes') for name, m in methods.items()}
    md = ['# GeoFusion benchmark report', '',
          '- date: %s' % summary['date'],
          '- commit: %s' % summary['commit'],
          '- machine: %s; %s; %s cores' % (machine['uname'], machine['cpu'], machine['cores']),
          '- suite: %s (%d scenes: %s)' % (summary['suite'], len(scenes), ', '.join(scenes)),
          '- made with: `%s`' % command, '',
          'Pooled over all scenes. Ground truth less than 10 %% visible is ignored (COCO '
          'crowd). Keyframes evaluated: %s.' % ', '.join('%s %s' % (k, v) for k, v in
                                                         n_keyframes.items()), '']

    md += ['## Table I: COCO bounding-box mAP (%)', '',
           'The headline (and every other figure here) takes the ground-truth boxes of the '
           'projected model points, like the methods\' own boxes (both amodal). Beside it: the '
           'same detections against the boxes of the visible instance masks (modal, as Mask '
           'R-CNN annotations); occluded objects make the two differ.', '']
    rows = [[n, _num(m['map50']), _num(m['map75']), _num(m['map50_95']),
             _num(m.get('map50_mask')), _num(m.get('map75_mask')), _num(m.get('map50_95_mask'))]
            for n, m in methods.items()]
    rows += [['paper: ' + n, _num(p['map50']), _num(p['map75']), _num(p['map50_95']), '', '', '']
             for n, p in PAPER.items()]
    md += _table(['method', 'mAP50', 'mAP75', 'mAP50:95', 'mask boxes: mAP50', 'mAP75',
                  'mAP50:95'], rows) + ['']

    md += ['## Table II: precision / recall at score 0.5', '']
    rows = [[n, _num(m['precision50'], 3), _num(m['recall50'], 3), _num(m['precision75'], 3),
             _num(m['recall75'], 3), '%d / %d / %d' % (m['tp50'], m['fp50'], m['gt50'])]
            for n, m in methods.items()]
    rows += [['paper: ' + n, _num(p['precision50'], 2), _num(p['recall50'], 2),
              _num(p['precision75'], 2), _num(p['recall75'], 2), '']
             for n, p in PAPER.items()]
    md += _table(['method', 'P (IoU 0.5)', 'R (IoU 0.5)', 'P (IoU 0.75)', 'R (IoU 0.75)',
                  'TP / FP / GT (IoU 0.5)'], rows) + ['']

    md += ['## Pose accuracy (ADD-S of true positives at IoU 0.5, score 0.5)', '',
           'AUC: the per-keyframe ADD-S AUC, YCB-Video\'s AUC up to 10 cm over every visible '
           'ground-truth instance of every keyframe (missed = worst); AUC 2 cm: area under the '
           'curve below, over true positives.', '']
    rows = [[n, str(m['adds_tp_count']), _num(m['adds_under_1cm'], 3),
             _num(m['adds_under_2cm'], 3), _num(m['adds_auc']), _num(m['adds_auc_2cm']),
             _num(None if m['adds_tp_median_m'] is None else 1000 * m['adds_tp_median_m'], 1)]
            for n, m in methods.items()]
    md += _table(['method', 'TPs', '< 1 cm', '< 2 cm', 'AUC (10 cm)', 'AUC (2 cm)',
                  'median (mm)'], rows) + ['']
    md += ['ADD (no symmetry; what ADD-S hides: a can turned about its axis): AUC up to 10 cm '
           'over the same ground truth, and the share under 2 cm.', '']
    rows = [[n, _num(m.get('add_auc')), _num(m.get('add_under_2cm'), 3)]
            for n, m in methods.items()]
    md += _table(['method', 'ADD AUC (10 cm)', 'ADD < 2 cm'], rows) + ['']
    md += ['## BOP metrics (VSD, MSSD, MSPD; the appearance\'s symmetries)', '',
           'Recall averaged over BOP19\'s thresholds (VSD: delta 15 mm, tau 5-50 % of the '
           'diameter x theta 0.05-0.5, the test depth the true scene rendered; MSSD 5-50 % of '
           'the diameter; MSPD 5-50 px at 640 px width), estimates matched to the targets (at '
           'least 10 % visible) by bop_toolkit\'s rule; AR the mean of the three (of MSSD and '
           'MSPD where VSD is n/a).', '']
    rows = [[n, _num(m.get('bop_ar'), 3), _num(m.get('bop_ar_vsd'), 3),
             _num(m.get('bop_ar_mssd'), 3), _num(m.get('bop_ar_mspd'), 3)]
            for n, m in methods.items()]
    md += _table(['method', 'AR', 'AR_VSD', 'AR_MSSD', 'AR_MSPD'], rows) + ['']
    classes = sorted({c for m in methods.values() for c in (m.get('bop_per_class') or {})})
    if classes:
        def cell(m, c):
            a = (m.get('bop_per_class') or {}).get(c) or {}
            return ' / '.join(_num(a.get(k), 2) for k in ('ar_vsd', 'ar_mssd', 'ar_mspd'))
        rows = [[c] + [cell(m, c) for m in methods.values()] for c in classes]
        md += ['Per class, AR_VSD / AR_MSSD / AR_MSPD:', '']
        md += _table(['class'] + list(methods), rows, numeric=False) + ['']
    if any(m['adds_missing'] for m in methods.values()):
        md += ['True positives without an ADD-S value (counted as infinite): %s.' % ', '.join(
            '%s %d' % (n, m['adds_missing']) for n, m in methods.items()), '']
    if 'adds_curve' in figures:
        md += ['![ADD-S accuracy curve](%s)' % figures['adds_curve'], '']

    md += ['## Contact graph (final maps, summed over scenes)', '',
           'Support contacts scored per object pair and type (a right pair with another type '
           'label is wrong), and per object pair whatever the type.', '']
    rows = [[n, _num(m['contact_precision'], 3), _num(m['contact_recall'], 3),
             _num(m['contact_f1'], 3), _num(m.get('contact_pair_precision'), 3),
             _num(m.get('contact_pair_recall'), 3), _num(m.get('contact_pair_f1'), 3),
             'n/a' if m['contact_true'] is None else '%d / %d / %d' % (
                 m['contact_correct'], m['contact_estimated'], m['contact_true'])]
            for n, m in methods.items()]
    md += _table(['method', 'P (pair + type)', 'R', 'F1', 'P (pair)', 'R', 'F1',
                  'correct / estimated / true (pair + type)'], rows) + ['']
    md += ['Every contact per kind (support, leaning at an angle, side by side), scored per '
           'object pair and kind.', '']
    rows = []
    for n, m in methods.items():
        if m.get('contact_support_true') is None:
            continue
        for kind in CONTACT_KINDS:
            p = 'contact_%s_' % kind
            rows.append([n, kind, _num(m[p + 'precision'], 3), _num(m[p + 'recall'], 3),
                         _num(m[p + 'f1'], 3), '%d / %d / %d' % (
                             m[p + 'correct'], m[p + 'estimated'], m[p + 'true'])])
    if rows:
        md += _table(['method', 'kind', 'P', 'R', 'F1', 'correct / estimated / true'],
                     rows) + ['']
    if 'contact_graph' in figures:
        md += ['![contact graph](%s)' % figures['contact_graph'], '']

    md += ['## Physical plausibility (final maps)', '']
    rows = [[n, _num(m['penetration_mean_mm'], 2), _num(m['penetration_max_mm'], 2),
             _num(m['float_gap_mean_mm'], 2), _num(m['float_gap_max_mm'], 2),
             str(m['physics_pairs'])] for n, m in methods.items()]
    md += _table(['method', 'penetration mean (mm)', 'penetration max (mm)', 'gap mean (mm)',
                  'gap max (mm)', 'values'], rows) + ['']
    md += stability_section(methods)
    md += plan_section(methods)
    rows = [[n, '%d / %d / %d' % (m['final_objects'], m['final_matched'],
                                  m['final_true_objects']),
             _num(None if m['final_adds_mean_m'] is None else 1000 * m['final_adds_mean_m']),
             _num(m['final_adds_under_1cm'], 3)] for n, m in methods.items()]
    md += ['Final maps:', ''] + _table(['method', 'objects / matched / true',
                                        'ADD-S mean (mm)', 'ADD-S < 1 cm'], rows) + ['']
    rows = [[n, 'n/a' if m.get('lifecycle_lost') is None else str(m['lifecycle_lost']),
             'n/a' if m.get('lifecycle_flip_flops') is None else str(m['lifecycle_flip_flops']),
             'n/a' if m.get('lifecycle_objects') is None else str(m['lifecycle_objects'])]
            for n, m in methods.items()]
    md += ['Object lifecycle (online maps; lost = at least half visible in 20 keyframes, yet not in '
           'the final map or out of the map for more than 10 keyframes after it entered; flip-flops'
           ' = returns after leaving):', ''] + _table(['method', 'lost', 'flip-flops',
                                                     'true objects'], rows) + ['']
    if any(m.get('removals') for m in methods.values()):
        rows = [[n, str(m['removals']), _num(m['removal_latency_mean'], 1),
                 _int(m['removal_latency_max']), str(m['removal_ghosts'])]
                for n, m in methods.items() if m.get('removals') is not None]
        md += ['Changed scenes (objects taken away, or moved: their old place): keyframes from the '
               'first keyframe after the change until the map let the object go, and the objects '
               'it still has at the end (ghosts):', ''] + _table(
                   ['method', 'removals', 'latency mean', 'latency max', 'ghosts'], rows) + ['']

    md += ['## The detector\'s persistent errors and the camera trajectory', '',
           'Phantoms: false objects the detector reports at one place in at least 5 keyframes; '
           'swaps: objects it reports as a look-alike class in at least 5 keyframes. "In the '
           'final map": an unmatched object there that they explain. ATE: RMSE of the camera '
           'positions after a rigid alignment, mean over scenes, beside that of the odometry '
           'the method was given.', '']
    rows = [[n, '%s of %s' % (_int(m.get('surviving_phantoms')),
                              _int(m.get('persistent_phantoms'))),
             '%s of %s' % (_int(m.get('surviving_swaps')), _int(m.get('persistent_swaps'))),
             '%s / %s' % (_int(m.get('class_changes')), _int(m.get('classes_kept'))),
             _num(m.get('ate_mm')), _num(m.get('odometry_ate_mm'))]
            for n, m in methods.items()]
    md += _table(['method', 'phantoms in the final map', 'swapped classes in the final map',
                  'look-alikes: classes changed / kept by the depth', 'ATE (mm)',
                  'odometry ATE (mm)'], rows) + ['']

    classes = sorted({c for m in methods.values() for c in (m.get('class_recall') or {})})
    if classes:
        md += ['## Final-map recall per class (mapped / present, summed over scenes)', '']
        rows = []
        for c in classes:
            row = [c]
            for m in methods.values():
                true, found = (m.get('class_recall') or {}).get(c, [0, 0])
                row.append('%d / %d' % (found, true) if true else '-')
            rows.append(row)
        md += _table(['class'] + list(methods), rows) + ['']

    md += ['## Time', '']
    rows = [[n, _num(m.get('ms_per_keyframe_mean')), _num(m['ms_per_keyframe_p50']),
             _num(m['ms_per_keyframe_p95']), _num(m['ms_per_keyframe_max']),
             _num(m['realtime_factor'], 3), _num(m['peak_rss_mb'], 0)]
            for n, m in methods.items()]
    md += ['The mean carries what is done only every N-th keyframe (B-SLAM solves stage I every '
           '10th keyframe, so its median is near 0).', '']
    md += _table(['method', 'ms / keyframe mean', 'p50', 'p95', 'max', 'real-time factor',
                  'peak memory (MB)'], rows) + ['']
    rows = [[n] + ['%s / %s' % (_num(m['ms_%s_p50' % s]), _num(m['ms_%s_p95' % s]))
                   for s in STAGES] for n, m in methods.items()]
    md += ['Per stage, ms per keyframe (p50 / p95):', '']
    md += _table(['method'] + [s.replace('_', ' ') for s in STAGES], rows) + ['']
    if 'timing' in figures:
        md += ['![time per keyframe](%s)' % figures['timing'], '']

    md += ['## Per scene', '']
    names = list(methods)
    for key, label, digits in (('map50_95', 'mAP50:95 (%)', 1),
                               ('precision50', 'precision (IoU 0.5, score 0.5)', 3),
                               ('recall50', 'recall (IoU 0.5, score 0.5)', 3),
                               ('adds_under_1cm', 'ADD-S < 1 cm share', 3),
                               ('contact_f1', 'contact F1', 3),
                               ('ate_mm', 'camera ATE (mm)', 1),
                               ('odometry_ate_mm', 'ATE of the odometry given (mm)', 1)):
        rows = [[s] + [_num((scenes[s].get(n) or {}).get(key), digits) if n in scenes[s]
                       else '-' for n in names] for s in scenes]
        md += ['### %s' % label, ''] + _table(['scene'] + names, rows) + ['']

    md += ['## Targets', '',
           'Suite %s: %s' % (summary['suite'], 'the targets of the suites with persistent '
                             'detector errors (bench, bench_rgb).' if summary['suite'] in
                             PERSISTENT_SUITES else 'the paper-reproduction targets (set for '
                             'independent detector errors, bench_iid).'), '']
    rows = [[t['target'], t['measured'], t['status']] for t in summary['targets']]
    md += _table(['target', 'measured', 'result'], rows, numeric=False) + ['']
    met = sum(t['met'] for t in summary['targets'])
    md += ['%d of %d targets met.' % (met, len(summary['targets'])), '']

    path = os.path.join(out_dir, 'report.md')
    with open(path, 'w') as f:
        f.write('\n'.join(md).rstrip('\n') + '\n')
    return path


def print_table(summary, file=None):
    """A short table of the pooled figures (to stdout by default)."""
    file = file or sys.stdout
    header = ('%-10s %6s %6s %8s %6s %6s %6s %7s %5s %7s %7s %7s %6s'
              % ('method', 'mAP50', 'mAP75', 'mAP50:95', 'P50', 'R50', 'AUC', 'ADD-S1', 'lost',
                 'ATE mm', 'cF1', 'p95 ms', 'RTF'))
    print('%s (%d scenes)' % (summary['suite'], len(summary['scenes'])), file=file)
    print(header, file=file)
    for name, m in summary['methods'].items():
        print('%-10s %6s %6s %8s %6s %6s %6s %7s %5s %7s %7s %7s %6s'
              % (name, _num(m['map50']), _num(m['map75']), _num(m['map50_95']),
                 _num(m['precision50'], 3), _num(m['recall50'], 3), _num(m['adds_auc']),
                 _num(m['adds_under_1cm'], 3), _int(m.get('lifecycle_lost')),
                 _num(m.get('ate_mm')), _num(m['contact_f1'], 3),
                 _num(m['ms_per_keyframe_p95']), _num(m['realtime_factor'], 3)), file=file)
    print('odometry ATE %s mm (mean over scenes)'
          % _num((summary['methods'].get(BASELINE) or {}).get('odometry_ate_mm')), file=file)


def write_combined_report(suite_dirs, out_dir):
    """OUT/report.md over several suites' reports (each DIR holds a summary.json and its
    figures): a table and the targets per suite, the figures linked. Raises EvalError."""
    md = ['# GeoFusion benchmark: all suites', '',
          'One section per suite; each suite\'s full report is report.md in its folder. '
          'bench: persistent DenseFusion-like detector errors; bench_rgb: a colour-only 6D '
          'estimator; bench_iid: independent errors, for the paper\'s tables '
          '(docs/BENCHMARK.md).', '']
    for directory in suite_dirs:
        path = os.path.join(directory, 'summary.json')
        try:
            with open(path) as f:
                summary = json.load(f)
        except (OSError, ValueError) as e:
            raise EvalError('%s: %s' % (path, e))
        rel = os.path.relpath(directory, out_dir)
        methods = summary.get('methods') or {}
        md += ['## %s' % summary.get('suite'), '',
               '- commit %s, %s; %d scenes; [full report](%s/report.md)' % (
                   summary.get('commit'), summary.get('date'), len(summary.get('scenes') or {}),
                   rel), '']
        rows = [[n, _num(m.get('map50_95')), _num(m.get('map75')), _num(m.get('map50_95_mask')),
                 _num(m.get('precision50'), 3), _num(m.get('recall50'), 3),
                 _num(m.get('adds_auc')),
                 '%s / %s' % (_int(m.get('final_matched')), _int(m.get('final_true_objects'))),
                 _int(m.get('lifecycle_lost')),
                 '%s + %s' % (_int(m.get('surviving_phantoms')), _int(m.get('surviving_swaps'))),
                 _num(m.get('ate_mm')), _num(m.get('odometry_ate_mm')),
                 _num(m.get('contact_f1'), 3), _num(m.get('contact_pair_f1'), 3)]
                for n, m in methods.items()]
        md += _table(['method', 'mAP50:95', 'mAP75', 'mAP50:95 (mask boxes)', 'P50', 'R50',
                      'ADD-S AUC', 'final map true / scene', 'lost', 'phantoms + swaps kept',
                      'ATE (mm)', 'odometry ATE (mm)', 'contact F1', 'contact F1 (pair)'],
                     rows) + ['']
        targets = summary.get('targets') or []
        md += _table(['target', 'measured', 'result'],
                     [[t['target'], t['measured'], t['status']] for t in targets],
                     numeric=False) + ['']
        md += ['%d of %d targets met.' % (sum(t['met'] for t in targets), len(targets)), '']
        for name in sorted(os.listdir(directory)):
            if name.endswith('.png'):
                md += ['![%s %s](%s/%s)' % (summary.get('suite'), name[:-4], rel, name)]
        md += ['']
    os.makedirs(out_dir, exist_ok=True)
    path = os.path.join(out_dir, 'report.md')
    with open(path, 'w') as f:
        f.write('\n'.join(md).rstrip('\n') + '\n')
    return path


# ---------------------------------------------------------------------------------------------

def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--eval-dir',
                        help='directory with <scene>/<method>.json evaluation files')
    parser.add_argument('--combine', nargs='+', metavar='SUITE_DIR',
                        help='instead: one report over these suites\' report folders')
    parser.add_argument('--out', required=True, help='output directory (made if missing)')
    parser.add_argument('--suite', help='suite name (default: the evaluation directory name)')
    parser.add_argument('--commit', help='commit measured (default: git rev-parse here)')
    parser.add_argument('--plot-scene', help='scene of the timing and contact graph figures '
                        '(default: the first)')
    parser.add_argument('--guard', action='store_true',
                        help='exit 1 unless GeoFusion is ahead of FbF on mAP50:95 and '
                        'precision50')
    try:
        args = parser.parse_args(argv)
    except SystemExit as e:  # bad arguments: 2 (--help: 0), also when called as a function
        return e.code
    if args.combine:
        try:
            path = write_combined_report(args.combine, args.out)
        except EvalError as e:
            print('bench_report: %s' % e, file=sys.stderr)
            return 2
        print('written: %s' % path)
        return 0
    if not args.eval_dir or not os.path.isdir(args.eval_dir):
        print('bench_report: no directory %s' % args.eval_dir, file=sys.stderr)
        return 2
    try:
        evals = load_evals(args.eval_dir)
    except EvalError as e:
        print('bench_report: %s' % e, file=sys.stderr)
        return 2
    if not evals:
        print('bench_report: no evaluation files in %s/<scene>/*.json' % args.eval_dir,
              file=sys.stderr)
        return 2
    scenes = scenes_of(evals)
    plot_scene = args.plot_scene or scenes[0]
    if plot_scene not in scenes:
        print('bench_report: --plot-scene %s is none of %s' % (plot_scene, ', '.join(scenes)),
              file=sys.stderr)
        return 2
    suite = args.suite or os.path.basename(os.path.normpath(args.eval_dir))
    commit = args.commit or git_commit()
    try:
        summary = summarize(evals, suite, commit)
    except (EvalError, KeyError, TypeError, ValueError) as e:
        print('bench_report: cannot evaluate: %s: %s' % (type(e).__name__, e), file=sys.stderr)
        return 2
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, 'summary.json'), 'w') as f:
        json.dump(json_ready(summary), f, indent=1, allow_nan=False)
    figures = write_figures(evals, summary, args.out, plot_scene)
    command = 'bench_report.py ' + shlex.join(argv)
    write_report(summary, args.out, figures, command)
    print_table(summary)
    print('written: %s' % os.path.join(args.out, 'report.md'))
    if args.guard:
        passed, message = guard(summary['methods'])
        print(message, file=sys.stdout if passed else sys.stderr)
        return 0 if passed else 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
