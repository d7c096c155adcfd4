#!/usr/bin/python3
"""Compares a run's final map (run_offline results, docs/results.md) with the recording's ground
truth (docs/dataset.md) and prints a short summary: objects found and true, false objects, mean
position error, contacts found and true, time per keyframe. (Symmetry-aware pose errors, ADD-S
on the models' points, and COCO mAP are the benchmark's.)

    evaluate_run.py --results RESULTS.yaml --ground-truth SCENE_gt.yaml [--max-distance 0.05]

Objects match one to one, same class, nearest first, centres within --max-distance. Contacts
compare object pairs (the table is -1) of matched objects with the true contact graph; support
contacts only, as the estimator infers them. Exit code 0, or 2 for unreadable files.
"""
import argparse
import math
import sys

import numpy as np
import yaml

LOADER = getattr(yaml, 'CSafeLoader', yaml.SafeLoader)


def match(estimated, truth, max_distance):
    """Greedy one-to-one matching by centre distance within a class: {estimated index: truth index}."""
    pairs = []
    for i, e in enumerate(estimated):
        for j, t in enumerate(truth):
            if e['class_name'] == t['class_name']:
                d = math.dist(e['map_object'][:3], t['pose'][:3])
                if d < max_distance:
                    pairs.append((d, i, j))
    out, used = {}, set()
    for d, i, j in sorted(pairs):
        if i not in out and j not in used:
            out[i] = j
            used.add(j)
    return out


def summarize(results, gt, max_distance=0.05):
    final = results['final_map']['objects']
    truth = gt['objects']
    m = match(final, truth, max_distance)
    seen = {t for f in gt['frames'] if f.get('keyframe') for t in f.get('detection_truth', [])
            if t >= 0}
    pos = [math.dist(final[i]['map_object'][:3], truth[j]['pose'][:3]) for i, j in m.items()]
    by_id = {o['id']: k for k, o in enumerate(final)}

    def truth_index(object_id):
        if object_id == -1:
            return -1
        k = by_id.get(object_id)
        return m.get(k) if k is not None else None

    est_pairs = set()
    for c in results['final_map'].get('contacts', []):
        a, b = truth_index(c['a']), truth_index(c['b'])
        if a is not None and b is not None and c.get('support', True):
            est_pairs.add(frozenset((a, b)))
    true_pairs = {frozenset((c['a'], c['b'])) for c in gt['contacts'] if c['support']}
    # Only contacts between objects the map could know (found, or the table).
    known = set(m.values()) | {-1}
    true_known = {p for p in true_pairs if p <= known}
    hits = len(est_pairs & true_known)
    times = sorted(k['timings_ms']['total'] for k in results['keyframes']) or [0.0]
    return {
        'objects_found': len(m), 'objects_true': len(truth), 'objects_seen': len(seen),
        'false_objects': len(final) - len(m),
        'position_error_mm': 1000 * float(np.mean(pos)) if pos else float('nan'),
        'contacts_found': len(est_pairs), 'contacts_correct': hits,
        'contacts_true': len(true_pairs), 'contacts_true_between_found': len(true_known),
        'ms_per_keyframe_p50': times[len(times) // 2],
        'ms_per_keyframe_p95': times[min(len(times) - 1, int(0.95 * (len(times) - 1) + 0.5))],
        'keyframes': len(results['keyframes']),
        'realtime_factor': results.get('realtime_factor', float('nan')),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--results', required=True)
    parser.add_argument('--ground-truth', required=True)
    parser.add_argument('--max-distance', type=float, default=0.05)
    args = parser.parse_args()
    try:
        with open(args.results) as f:
            results = yaml.load(f, Loader=LOADER)
        with open(args.ground_truth) as f:
            gt = yaml.load(f, Loader=LOADER)
        s = summarize(results, gt, args.max_distance)
    except (OSError, yaml.YAMLError, KeyError, TypeError) as e:
        print('evaluate_run: cannot read the files: %s' % e, file=sys.stderr)
        return 2
    print('%s on %s: %d keyframes' % (results['method'], results['source'], s['keyframes']))
    print('  objects: %d found of %d in the scene (%d detected at least once), %d false'
          % (s['objects_found'], s['objects_true'], s['objects_seen'], s['false_objects']))
    print('  position error of the found objects: %.1f mm (mean)' % s['position_error_mm'])
    print('  support contacts: %d found, %d of them true; %d true (%d between found objects and '
          'the table)' % (s['contacts_found'], s['contacts_correct'], s['contacts_true'],
                          s['contacts_true_between_found']))
    print('  time a keyframe: %.1f ms median, %.1f ms p95; real-time factor %.2f'
          % (s['ms_per_keyframe_p50'], s['ms_per_keyframe_p95'], s['realtime_factor']))
    return 0


if __name__ == '__main__':
    sys.exit(main())
