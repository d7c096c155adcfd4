#!/usr/bin/env python3
"""Tests of src/tools/bench_report.py on small hand-made evaluation files with known answers.

    ~/.cache/geofusion/venv/bin/python -m unittest test/python/test_bench_report.py   (from the
    package root), or python3 test/python/test_bench_report.py

The scenes have two keyframes with four objects each, one class an object, boxes 100 x 100 px,
so that a perfect detector scores 100 mAP and every deviation has a figure worked out by hand.
"""
import contextlib
import copy
import io
import json
import math
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'src',
                                'tools'))
try:
    import bench_report  # noqa: E402
except ImportError as e:  # pycocotools is in the package's venv, not the system Python
    raise ImportError('%s: run with ~/.cache/geofusion/venv/bin/python' % e) from e

# Four objects (category = object number), 100 x 100 px, well apart.
BOXES = {1: [20.0, 20.0, 100.0, 100.0], 2: [200.0, 20.0, 100.0, 100.0],
         3: [20.0, 200.0, 100.0, 100.0], 4: [200.0, 200.0, 100.0, 100.0]}
SLUGS = {'FbF': 'fbf', 'B-SLAM': 'bslam', 'R-Front': 'rfront', 'GeoFusion': 'geofusion'}


def make_eval(method='GeoFusion', scene='s1', n_images=2, detect=None, extra_gt=(),
              extra_det=(), contacts=None):
    """An evaluation file: objects 1..4 on every image as ground truth (annotation id =
    10 * image + object); detect(image, object) -> None (missed) or (bbox, score, adds_m) makes
    the detections. extra_gt: (object, bbox, iscrowd) on every image; extra_det: (object, bbox,
    score) on every image."""
    if detect is None:
        def detect(image, obj):
            return BOXES[obj], 0.9, 0.0
    ev = {'format': bench_report.FORMAT, 'scene': scene, 'method': method,
          'image_size': [640, 480],
          'categories': [{'id': c, 'name': '%03d_object_%d' % (c, c)} for c in range(1, 6)],
          'images': [{'id': i, 'stamp': 100.0 + i} for i in range(n_images)],
          'annotations': [], 'detections': []}
    for i in range(n_images):
        gts = [(obj, box, 0) for obj, box in BOXES.items()] + list(extra_gt)
        for obj, box, crowd in gts:
            ev['annotations'].append({'id': 10 * i + obj, 'image_id': i, 'category_id': obj,
                                      'bbox': list(box), 'area': box[2] * box[3],
                                      'iscrowd': crowd, 'object': obj,
                                      'visible_fraction': 0.05 if crowd else 0.8})
        for obj in BOXES:
            d = detect(i, obj)
            if d is None:
                continue
            box, score, adds = d
            ev['detections'].append({'id': len(ev['detections']) + 1, 'image_id': i,
                                     'category_id': obj, 'bbox': list(box), 'score': score,
                                     'object_id': 100 + obj, 'adds_m': {str(10 * i + obj): adds}})
        for obj, box, score in extra_det:
            ev['detections'].append({'id': len(ev['detections']) + 1, 'image_id': i,
                                     'category_id': obj, 'bbox': list(box), 'score': score,
                                     'object_id': 100 + obj, 'adds_m': {}})
    ev['final_map'] = {'objects': 4, 'matched': 4, 'true_objects': 4,
                       'adds_m': [0.003, 0.004, 0.005, 0.02], 'contacts': contacts,
                       'penetration_mm': [0.0, 1.0, 2.0], 'gap_mm': [0.5, 1.5]}
    ev['timings_ms'] = {'consistency': [1.0] * n_images, 'association': [2.0] * n_images,
                        'lifecycle': [0.5] * n_images,
                        'stage_one': [3.0] * n_images, 'relations': [1.0] * n_images,
                        'stage_two': [3.0] * n_images,
                        'total': [10.0 + 10.0 * i for i in range(n_images)]}
    ev.update(recording_duration_s=10.0, wall_time_s=1.0, realtime_factor=0.1,
              peak_rss_mb=500.0)
    ev['contact_graph'] = {
        'true_objects': [{'index': k, 'class_name': '%03d_object_%d' % (k + 1, k + 1),
                          'xy': [0.1 * k, 0.0], 'z': 0.8} for k in range(4)],
        'true_contacts': [{'a': -1, 'b': 0, 'type': 'P2P', 'support': True},
                          {'a': 0, 'b': 1, 'type': 'P2C', 'support': False},
                          {'a': 2, 'b': 3, 'type': 'C2C', 'support': True}],
        'estimated_objects': [{'id': 100 + k, 'class_name': '%03d_object_%d' % (k + 1, k + 1),
                               'xy': [0.1 * k + 0.002, 0.001], 'z': 0.8, 'match': k}
                              for k in range(4)] + [{'id': 200, 'class_name': 'x', 'xy': [0.5, 0.5],
                                                     'z': 0.8, 'match': -1}],
        'estimated_contacts': [{'a': -1, 'b': 100, 'type': 'P2P', 'support': True,
                                'correct': True},
                               {'a': 102, 'b': 103, 'type': 'C2C', 'support': True,
                                'correct': False}]}
    return ev


def shifted(box, dx):
    return [box[0] + dx, box[1], box[2], box[3]]


class CocoMetricsTest(unittest.TestCase):

    def test_perfect(self):
        m = bench_report.method_summary([make_eval()])
        for key in ('map50', 'map75', 'map50_95'):
            self.assertAlmostEqual(m[key], 100.0, places=6, msg=key)
        for key in ('precision50', 'recall50', 'precision75', 'recall75', 'adds_under_1cm',
                    'adds_under_2cm'):
            self.assertAlmostEqual(m[key], 1.0, places=9, msg=key)
        self.assertAlmostEqual(m['adds_auc'], 100.0)
        self.assertEqual((m['tp50'], m['fp50'], m['gt50']), (8, 0, 8))

    def test_pooled_scenes_with_the_same_ids(self):
        # Both files use image ids 0, 1 and annotation ids 1..14: the pooled evaluation must
        # renumber them, else one scene's detections would match the other's ground truth.
        a = make_eval(scene='s1')
        b = make_eval(scene='s2', detect=lambda i, o: None if o == 1 else (BOXES[o], 0.9, 0.0))
        m = bench_report.method_summary([a, b])
        self.assertEqual((m['tp50'], m['fp50'], m['gt50']), (14, 0, 16))
        self.assertAlmostEqual(m['recall50'], 14 / 16)

    def test_one_object_missed(self):
        ev = make_eval(detect=lambda i, o: None if o == 4 else (BOXES[o], 0.9, 0.0))
        m = bench_report.method_summary([ev])
        self.assertAlmostEqual(m['recall50'], 0.75)
        self.assertAlmostEqual(m['precision50'], 1.0)
        # Errors 0, 0, 0, infinite per image: 100 * (1 - mean(min(e, 0.1)) / 0.1) = 75.
        self.assertAlmostEqual(m['adds_auc'], 75.0)
        self.assertAlmostEqual(m['adds_under_1cm'], 1.0)
        # Category 4 is never found: AP 0 there, 100 in the other three.
        self.assertAlmostEqual(m['map50'], 75.0, places=6)

    def test_shifted_detection(self):
        dx = 25.0
        # Hand computation: overlap (100 - 25) x 100 = 7500, union 2 x 10000 - 7500 = 12500.
        iou = (100.0 - dx) * 100.0 / (2 * 100.0 * 100.0 - (100.0 - dx) * 100.0)
        self.assertAlmostEqual(iou, 0.6)
        self.assertTrue(0.5 < iou < 0.75)

        def detect(i, o):
            return (shifted(BOXES[o], dx), 0.9, 0.013) if o == 4 else (BOXES[o], 0.9, 0.004)
        m = bench_report.method_summary([make_eval(detect=detect)])
        self.assertEqual((m['tp50'], m['fp50']), (8, 0))
        self.assertEqual((m['tp75'], m['fp75']), (6, 2))
        self.assertAlmostEqual(m['precision50'], 1.0)
        self.assertAlmostEqual(m['recall50'], 1.0)
        self.assertAlmostEqual(m['precision75'], 0.75)
        self.assertAlmostEqual(m['recall75'], 0.75)
        self.assertAlmostEqual(m['map50'], 100.0, places=6)
        self.assertAlmostEqual(m['map75'], 75.0, places=6)
        # The shifted detections' 1.3 cm shows up: 6 of 8 true positives under 1 cm, all under 2.
        self.assertAlmostEqual(m['adds_under_1cm'], 0.75)
        self.assertAlmostEqual(m['adds_under_2cm'], 1.0)
        # mean error (6 x 0.004 + 2 x 0.013) / 8 = 0.00625 m: AUC 100 * (1 - 0.0625).
        self.assertAlmostEqual(m['adds_auc'], 93.75)
        x, y = bench_report.adds_curve(m['_adds_tp_m'])
        self.assertAlmostEqual(y[x.searchsorted(0.005)], 0.75)
        self.assertAlmostEqual(y[-1], 1.0)  # every error < 2 cm

    def test_crowd_ground_truth_is_ignored(self):
        crowd_box = [400.0, 300.0, 60.0, 60.0]
        ev = make_eval(extra_gt=[(5, crowd_box, 1)], extra_det=[(5, crowd_box, 0.95)])
        m = bench_report.method_summary([ev])
        self.assertEqual((m['tp50'], m['fp50'], m['gt50']), (8, 0, 8))
        self.assertAlmostEqual(m['precision50'], 1.0)
        self.assertAlmostEqual(m['recall50'], 1.0)
        self.assertEqual(m['adds_missing'], 0)
        self.assertEqual(m['adds_tp_count'], 8)
        # The same box as plain ground truth would be a ninth true positive.
        plain = make_eval(extra_gt=[(5, crowd_box, 0)], extra_det=[(5, crowd_box, 0.95)])
        self.assertEqual(bench_report.method_summary([plain])['tp50'], 10)

    def test_false_positive(self):
        ev = make_eval(extra_det=[(1, [400.0, 300.0, 50.0, 50.0], 0.8)])
        m = bench_report.method_summary([ev])
        self.assertEqual((m['tp50'], m['fp50']), (8, 2))
        self.assertAlmostEqual(m['precision50'], 0.8)
        self.assertAlmostEqual(m['recall50'], 1.0)

    def test_low_score_detection(self):
        ev = make_eval(detect=lambda i, o: (BOXES[o], 0.3 if o == 2 else 0.9, 0.0))
        m = bench_report.method_summary([ev])
        self.assertEqual((m['tp50'], m['fp50'], m['gt50']), (6, 0, 8))
        self.assertAlmostEqual(m['precision50'], 1.0)
        self.assertAlmostEqual(m['recall50'], 0.75)
        # mAP takes every score: still perfect.
        self.assertAlmostEqual(m['map50_95'], 100.0, places=6)
        # A low-score detection alone is no true positive for ADD-S either: 2 of 8 missed.
        self.assertAlmostEqual(m['adds_auc'], 75.0)

    def test_no_detections(self):
        m = bench_report.method_summary([make_eval(detect=lambda i, o: None)])
        self.assertEqual((m['map50'], m['map75'], m['map50_95']), (0.0, 0.0, 0.0))
        self.assertIsNone(m['precision50'])
        self.assertEqual(m['recall50'], 0.0)
        self.assertIsNone(m['adds_under_1cm'])
        self.assertEqual(m['adds_auc'], 0.0)


class OtherMetricsTest(unittest.TestCase):

    def test_contacts_summed_over_scenes(self):
        a = make_eval(scene='s1', contacts={'true': 10, 'estimated': 8, 'correct': 6})
        b = make_eval(scene='s2', contacts={'true': 14, 'estimated': 12, 'correct': 10})
        c = bench_report.contact_metrics([a, b])
        p, r = 16 / 20, 16 / 24
        self.assertAlmostEqual(c['contact_precision'], p)
        self.assertAlmostEqual(c['contact_recall'], r)
        self.assertAlmostEqual(c['contact_f1'], 2 * p * r / (p + r))
        self.assertAlmostEqual(c['contact_f1'], 8 / 11)
        # A scene without contacts adds nothing.
        c = bench_report.contact_metrics([a, make_eval(scene='s3')])
        self.assertAlmostEqual(c['contact_precision'], 0.75)
        self.assertAlmostEqual(c['contact_recall'], 0.6)

    def test_null_contacts(self):
        c = bench_report.contact_metrics([make_eval(), make_eval(scene='s2')])
        self.assertIsNone(c['contact_precision'])
        self.assertIsNone(c['contact_recall'])
        self.assertIsNone(c['contact_f1'])
        c = bench_report.contact_metrics([make_eval(contacts={'true': 3, 'estimated': 0,
                                                              'correct': 0})])
        self.assertIsNone(c['contact_precision'])
        self.assertEqual(c['contact_recall'], 0.0)
        self.assertIsNone(c['contact_f1'])

    def test_contacts_per_kind_summed_over_scenes(self):
        def kinds(support, leaning, side):
            return {k: dict(zip(('true', 'estimated', 'correct'), v))
                    for k, v in (('support', support), ('leaning', leaning), ('side', side))}
        a = make_eval(scene='s1', contacts={'true': 10, 'estimated': 8, 'correct': 6,
                                            'by_kind': kinds((10, 8, 6), (2, 1, 1), (4, 0, 0))})
        b = make_eval(scene='s2', contacts={'true': 4, 'estimated': 4, 'correct': 4,
                                            'by_kind': kinds((4, 4, 4), (0, 3, 0), (2, 2, 1))})
        c = bench_report.contact_kind_metrics([a, b])
        self.assertAlmostEqual(c['contact_support_precision'], 10 / 12)
        self.assertAlmostEqual(c['contact_support_recall'], 10 / 14)
        self.assertAlmostEqual(c['contact_leaning_precision'], 1 / 4)
        self.assertAlmostEqual(c['contact_leaning_recall'], 1 / 2)
        self.assertAlmostEqual(c['contact_leaning_f1'], 2 * 0.25 * 0.5 / 0.75)
        self.assertEqual((c['contact_side_correct'], c['contact_side_estimated'],
                          c['contact_side_true']), (1, 2, 6))
        # Files without per-kind counts (another method, older files): no figure.
        c = bench_report.contact_kind_metrics([make_eval()])
        self.assertIsNone(c['contact_leaning_f1'])
        self.assertIsNone(c['contact_side_true'])

    def test_class_recall_from_the_final_maps(self):
        # make_eval's final map matches true objects 0..3, one class each; a second scene where
        # object 2 is missed.
        a = make_eval(scene='s1')
        b = make_eval(scene='s2')
        for o in b['contact_graph']['estimated_objects']:
            if o['match'] == 2:
                o['match'] = -1
        recall = bench_report.class_recall([a, b])
        self.assertEqual(recall['003_object_3'], [2, 1])
        self.assertEqual(recall['001_object_1'], [2, 2])
        m = bench_report.method_summary([a, b])
        self.assertEqual(m['class_recall']['003_object_3'], [2, 1])

    def test_physics_and_time(self):
        m = bench_report.method_summary([make_eval(), make_eval(scene='s2', n_images=4)])
        self.assertAlmostEqual(m['penetration_mean_mm'], 1.0)
        self.assertAlmostEqual(m['penetration_max_mm'], 2.0)
        self.assertAlmostEqual(m['float_gap_mean_mm'], 1.0)
        self.assertAlmostEqual(m['float_gap_max_mm'], 1.5)
        # totals 10, 20 and 10, 20, 30, 40: median 20, mean 130 / 6, max 40
        self.assertAlmostEqual(m['ms_per_keyframe_p50'], 20.0)
        self.assertAlmostEqual(m['ms_per_keyframe_mean'], 130.0 / 6)
        self.assertAlmostEqual(m['ms_per_keyframe_max'], 40.0)
        self.assertAlmostEqual(m['ms_stage_one_p95'], 3.0)
        self.assertAlmostEqual(m['realtime_factor'], 0.1)
        self.assertEqual(m['final_true_objects'], 8)


class PersistentErrorMetricsTest(unittest.TestCase):

    def test_mask_boxes_score_against_the_visible_pixels(self):
        # Masks a quarter of each projected box (the objects' lower-right parts hidden): the
        # projected-model boxes stay perfect, the same detections overlap the mask boxes at IoU
        # 0.25 only, below every COCO threshold.
        ev = make_eval()
        for a in ev['annotations']:
            x, y, w, h = a['bbox']
            a['mask_bbox'] = [x, y, w / 2, h / 2]
        m = bench_report.method_summary([ev])
        self.assertAlmostEqual(m['map50_95'], 100.0, places=6)
        self.assertAlmostEqual(m['map50_95_mask'], 0.0, places=6)
        # Files without mask boxes: not measured, nothing else changes.
        m = bench_report.method_summary([make_eval()])
        self.assertIsNone(m['map50_95_mask'])
        self.assertAlmostEqual(m['map50_95'], 100.0, places=6)

    def test_contacts_per_pair_and_type(self):
        a = make_eval(contacts={'true': 4, 'estimated': 4, 'correct': 2, 'true_pairs': 4,
                                'estimated_pairs': 4, 'correct_pairs': 3})
        c = bench_report.contact_metrics([a])
        self.assertAlmostEqual(c['contact_precision'], 0.5)
        self.assertAlmostEqual(c['contact_pair_precision'], 0.75)
        self.assertAlmostEqual(c['contact_pair_f1'], 0.75)

    def test_persistent_suite_targets(self):
        def with_errors(method, lost, phantoms, auc_adds):
            ev = make_eval(method, detect=lambda i, o: (BOXES[o], 0.9, auc_adds))
            ev['final_map'].update(persistent_phantoms=2, surviving_phantoms=phantoms,
                                   persistent_swaps=1, surviving_swaps=0)
            ev['trajectory'] = {'ate_rmse_m': 0.004, 'odometry_ate_rmse_m': 0.006}
            ev['lifecycle'] = {'lost': lost, 'flip_flops': 0, 'objects': [{}] * 4}
            return ev
        # FbF at 5 cm ADD-S (AUC 50), GeoFusion at 1 cm (AUC 90): 40 points above.
        evals = [with_errors('FbF', 0, 2, 0.05), with_errors('GeoFusion', 1, 1, 0.01)]
        summary = bench_report.summarize(evals, 'bench', 'x')
        targets = {t['target']: t for t in summary['targets']}
        auc = targets['per-keyframe ADD-S AUC: GeoFusion >= FbF + 10 points']
        self.assertTrue(auc['met'])
        self.assertEqual(auc['measured'], '90.0 vs 50.0')
        lost = targets['lost objects: GeoFusion none']
        self.assertFalse(lost['met'])
        self.assertEqual(lost['measured'], '1 of 4')
        kept = targets['persistent phantoms and swapped classes in the final maps: GeoFusion none']
        self.assertEqual(kept['measured'], '1 of 2 phantoms, 0 of 1 swaps')
        self.assertFalse(kept['met'])
        self.assertNotIn('mAP50:95: GeoFusion >= 1.6 x FbF', targets)
        self.assertAlmostEqual(summary['GeoFusion']['ate_mm'], 4.0)
        self.assertAlmostEqual(summary['GeoFusion']['odometry_ate_mm'], 6.0)
        # The independent-error suite has the paper's targets instead.
        targets = {t['target'] for t in bench_report.summarize(evals, 'bench_iid', 'x')['targets']}
        self.assertIn('mAP50:95: GeoFusion >= 1.6 x FbF', targets)
        self.assertNotIn('lost objects: GeoFusion none', targets)

    def test_plan_pooled_over_scenes_with_its_target(self):
        def planned(method, scene, unsafe, first, predicted, correct, in_physics=0):
            ev = make_eval(method, scene=scene)
            ev['scene_graph'] = {'removal_order': [3, 1, 2], 'true_steps': 3,
                                 'unsafe_steps': unsafe, 'steps_under_missed_objects': 1,
                                 'unsafe_steps_in_physics': in_physics,
                                 'first_unsafe_step': first, 'warnings': [],
                                 'free_to_pick': {'predicted': predicted, 'correct': correct,
                                                  'true': 2}}
            return ev
        evals = [planned('GeoFusion', 's1', 0, '', 2, 2),
                 planned('GeoFusion', 's2', 2, 'took box #1 (true) before mug #4 (true) '
                         'resting or leaning on it', 3, 1, in_physics=1),
                 planned('FbF', 's1', 1, 'took x', 3, 2)]
        plan = bench_report.plan_metrics(evals[:2])
        self.assertEqual(plan['plan_scenes'], 2)
        self.assertEqual(plan['plan_steps'], 6)
        self.assertEqual(plan['plan_unsafe_steps'], 2)
        self.assertAlmostEqual(plan['plan_unsafe_per_scene'], 1.0)
        self.assertEqual(plan['plan_unsafe_max_scene'], 2)
        self.assertEqual(plan['plan_steps_under_missed'], 2)
        self.assertEqual(plan['plan_unsafe_in_physics'], 1)
        self.assertTrue(plan['plan_first_unsafe'].startswith('s2: took box #1'))
        self.assertAlmostEqual(plan['free_precision'], 3 / 5)
        self.assertIsNone(bench_report.plan_metrics([make_eval()])['plan_scenes'])
        summary = bench_report.summarize(evals, 'bench', 'x')
        target = {t['target']: t for t in summary['targets']}[
            'plan: GeoFusion 0 unsafe removal steps of true objects']
        self.assertFalse(target['met'])
        self.assertEqual(target['measured'], '2 in 2 scenes (max 2 in one; 1 of them disturb '
                         'another object in physics)')
        section = '\n'.join(bench_report.plan_section(
            {'GeoFusion': summary['GeoFusion'], 'FbF': summary['FbF']}))
        self.assertIn('| GeoFusion | 6 | 2 | 1 | 1.00 | 2 | 3 / 5 | 0.600 |', section)
        self.assertTrue(section.startswith('## The support graph as a plan'), section)
        self.assertNotIn('plan: GeoFusion 0 unsafe removal steps of true objects',
                         {t['target'] for t in bench_report.summarize(
                             evals, 'bench_iid', 'x')['targets']})

    def test_removals_of_changed_scenes(self):
        a = make_eval(scene='s1')
        a['lifecycle'] = {'lost': 0, 'flip_flops': 0, 'objects': [{}] * 4, 'removals': 3,
                          'ghosts': 1, 'removal_latencies': [0, 4]}
        b = make_eval(scene='s2')
        b['lifecycle'] = {'lost': 0, 'flip_flops': 0, 'objects': [{}] * 4}  # a static scene
        f = bench_report.lifecycle_figures([a, b])
        self.assertEqual((f['removals'], f['removal_ghosts'], f['removal_latency_max']), (3, 1, 4))
        self.assertAlmostEqual(f['removal_latency_mean'], 2.0)
        summary = bench_report.summarize([a, b], 'bench', 'x')
        target = [t for t in summary['targets'] if t['target'].startswith('changed scenes')]
        self.assertEqual(len(target), 1)
        self.assertFalse(target[0]['met'])  # a ghost
        self.assertEqual(target[0]['measured'], '3 removals, 1 ghosts, latency max 4 keyframes')
        # Static scenes only: no figure, no target.
        f = bench_report.lifecycle_figures([b])
        self.assertEqual(f['removals'], 0)
        self.assertIsNone(f['removal_latency_max'])


def write_evals(directory, evals):
    for ev in evals:
        os.makedirs(os.path.join(directory, ev['scene']), exist_ok=True)
        with open(os.path.join(directory, ev['scene'], SLUGS[ev['method']] + '.json'), 'w') as f:
            json.dump(ev, f)


def run_main(argv):
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        return bench_report.main(argv)


def reject_constant(name):
    raise ValueError('non-finite number %s in summary.json' % name)


class MainTest(unittest.TestCase):

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.eval_dir = os.path.join(self.tmp.name, 'evals')
        self.out = os.path.join(self.tmp.name, 'report')

    def tearDown(self):
        self.tmp.cleanup()

    def test_guard(self):
        good = make_eval(method='GeoFusion', contacts={'true': 3, 'estimated': 3, 'correct': 3})
        poor = make_eval(method='FbF', detect=lambda i, o: None if o == 4 else
                         (shifted(BOXES[o], 10.0), 0.9, 0.02),
                         extra_det=[(1, [400.0, 300.0, 50.0, 50.0], 0.8)])
        write_evals(self.eval_dir, [good, poor])
        args = ['--eval-dir', self.eval_dir, '--out', self.out, '--commit', 'test', '--guard']
        self.assertEqual(run_main(args), 0)
        # Swap the roles: GeoFusion now worse than FbF.
        worse, better = copy.deepcopy(poor), copy.deepcopy(good)
        worse['method'], better['method'] = 'GeoFusion', 'FbF'
        write_evals(self.eval_dir, [worse, better])
        self.assertEqual(run_main(args), 1)
        # Without --guard the same evaluation is no error.
        self.assertEqual(run_main(args[:-1]), 0)

    def test_bad_input(self):
        self.assertEqual(run_main(['--out', self.out]), 2)
        self.assertEqual(run_main(['--eval-dir', self.eval_dir, '--out', self.out]), 2)
        os.makedirs(self.eval_dir)
        self.assertEqual(run_main(['--eval-dir', self.eval_dir, '--out', self.out]), 2)
        write_evals(self.eval_dir, [make_eval()])
        self.assertEqual(run_main(['--eval-dir', self.eval_dir, '--out', self.out,
                                   '--plot-scene', 'nowhere']), 2)

    def test_report_and_summary(self):
        evals = []
        for scene in ('s1', 's2'):
            evals += [
                make_eval('FbF', scene, detect=lambda i, o: None if o == 4 else
                          (shifted(BOXES[o], 25.0), 0.9, 0.013),
                          extra_det=[(1, [400.0, 300.0, 50.0, 50.0], 0.8)]),
                # B-SLAM finds nothing at all.
                make_eval('B-SLAM', scene, detect=lambda i, o: None,
                          contacts={'true': 3, 'estimated': 0, 'correct': 0}),
                make_eval('R-Front', scene, contacts={'true': 3, 'estimated': 4, 'correct': 2}),
                make_eval('GeoFusion', scene, contacts={'true': 3, 'estimated': 3,
                                                        'correct': 3})]
        write_evals(self.eval_dir, evals)
        code = run_main(['--eval-dir', self.eval_dir, '--out', self.out, '--suite', 'bench_iid',
                         '--commit', 'abc1234', '--plot-scene', 's2', '--guard'])
        self.assertEqual(code, 0)
        for name in ('report.md', 'summary.json', 'adds_curve.png', 'timing_s2.png',
                     'contact_graph_s2.png'):
            self.assertGreater(os.path.getsize(os.path.join(self.out, name)), 0, name)
        with open(os.path.join(self.out, 'summary.json')) as f:
            text = f.read()
        summary = json.loads(text, parse_constant=reject_constant)
        self.assertEqual((summary['suite'], summary['commit']), ('bench_iid', 'abc1234'))
        for key in ('date', 'machine', 'methods', 'scenes'):
            self.assertIn(key, summary)
        self.assertEqual(list(summary['methods']), ['FbF', 'B-SLAM', 'R-Front', 'GeoFusion'])
        for name in summary['methods']:
            for key in bench_report.REQUIRED_KEYS:
                self.assertIn(key, summary['methods'][name], '%s %s' % (name, key))
                self.assertIn(key, summary[name], '%s %s' % (name, key))
                for scene in ('s1', 's2'):
                    self.assertIn(key, summary['scenes'][scene][name])
        self.assertAlmostEqual(summary['GeoFusion']['map50'], 100.0, places=6)
        self.assertEqual(summary['B-SLAM']['map50_95'], 0.0)
        self.assertIsNone(summary['B-SLAM']['precision50'])
        self.assertIsNone(summary['FbF']['contact_f1'])
        self.assertAlmostEqual(summary['R-Front']['contact_precision'], 0.5)
        self.assertAlmostEqual(summary['FbF']['recall50'], 0.75)
        self.assertAlmostEqual(summary['FbF']['adds_under_1cm'], 0.0)
        self.assertNotIn('_adds_tp_m', summary['FbF'])

        def finite(obj):
            if isinstance(obj, dict):
                return all(finite(v) for v in obj.values())
            if isinstance(obj, list):
                return all(finite(v) for v in obj)
            return not isinstance(obj, float) or math.isfinite(obj)
        self.assertTrue(finite(summary))

        with open(os.path.join(self.out, 'report.md')) as f:
            report = f.read()
        for text in ('Table I', 'Table II', 'Targets', 'abc1234', '73.4', '0.99',
                     '### camera ATE (mm)', '### ATE of the odometry given (mm)',
                     '](adds_curve.png)', '](timing_s2.png)', '](contact_graph_s2.png)',
                     'n/a'):
            self.assertIn(text, report)
        targets = {t['target']: t for t in summary['targets']}
        self.assertTrue(targets['mAP50:95: GeoFusion >= 1.6 x FbF']['met'])
        self.assertEqual(targets['time per keyframe, p95: GeoFusion < 50.0 ms']['status'], 'met')
        rtf = targets['real-time factor: GeoFusion < 0.200']
        self.assertTrue(rtf['met'])  # 0.1
        ahead = targets['mAP50:95: GeoFusion ahead of every other method']
        self.assertFalse(ahead['met'])  # R-Front is as good (a tie)
        self.assertIn('missed by 0.0', ahead['status'])

        # One report over two suites' folders: a section and the targets per suite.
        other = os.path.join(self.tmp.name, 'report2')
        self.assertEqual(run_main(['--eval-dir', self.eval_dir, '--out', other, '--suite',
                                   'bench', '--commit', 'abc1234']), 0)
        combined = os.path.join(self.tmp.name, 'all')
        self.assertEqual(run_main(['--combine', self.out, other, '--out', combined]), 0)
        with open(os.path.join(combined, 'report.md')) as f:
            text = f.read()
        for piece in ('## bench_iid', '## bench', '../report/report.md', 'lost objects',
                      'GeoFusion >= 1.6 x FbF', '](../report2/adds_curve.png)'):
            self.assertIn(piece, text)
        self.assertEqual(run_main(['--combine', os.path.join(self.tmp.name, 'nowhere'),
                                   '--out', combined]), 2)


if __name__ == '__main__':
    unittest.main()
