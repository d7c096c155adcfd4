#!/usr/bin/env python3
"""Rows of docs/BENCHMARK.md's per-suite tables from a suite's summary.json (bench_report.py's):

    doc_rows.py results/<suite>/summary.json
    doc_rows.py --headline results/bench/summary.json results/bench_rgb/summary.json ...

Prints the methods' table (the columns of docs/BENCHMARK.md "Latest figures"), GeoFusion's
contacts per kind, the changed-scene line and the targets; with --headline, README's table (every
method of every suite named)."""
import json
import sys


def f(v, fmt):
    return 'n/a' if v is None else fmt % v


METHODS = ('FbF', 'FbF-R', 'B-SLAM', 'R-Front', 'GeoFusion')


def headline(paths):
    """README's benchmark table: one row a method and suite."""
    print('| suite | method | mAP75 | mAP50:95 | P50 / R50 | per-keyframe ADD-S AUC '
          '| final map true of true (false) | lost | camera ATE / odometry (mm) | p95 ms |')
    print('|---|---|---:|---:|---|---:|---|---:|---|---:|')
    for path in paths:
        s = json.load(open(path))
        suite = s.get('suite') or path.rstrip('/').split('/')[-2]
        for name in METHODS:
            m = s.get(name)
            if not m:
                continue
            false = m['final_objects'] - m['final_matched']
            print('| %s | %s | %s | %s | %s / %s | %s | %d of %d (%d) | %s | %s / %s | %s |' % (
                suite, name, f(m['map75'], '%.1f'), f(m['map50_95'], '%.1f'),
                f(m['precision50'], '%.3f'), f(m['recall50'], '%.3f'), f(m['adds_auc'], '%.1f'),
                m['final_matched'], m['final_true_objects'], false,
                f(m['lifecycle_lost'], '%d'), f(m['ate_mm'], '%.1f'),
                f(m['odometry_ate_mm'], '%.1f'), f(m['ms_per_keyframe_p95'], '%.1f')))


def main():
    if sys.argv[1] == '--headline':
        headline(sys.argv[2:])
        return
    s = json.load(open(sys.argv[1]))
    print('| method | mAP50 | mAP75 | mAP50:95 | mAP50:95 mask boxes | P50 / R50 | per-keyframe ADD-S AUC '
          '| ADD-S < 1 cm | final map objects / true / of | lost / flip-flops | phantoms + swaps kept '
          '| ATE / odometry (mm) | support contact F1 (pair+type / pair) | penetration mean (mm) '
          '| p95 ms | RTF |')
    print('|---|---:|---:|---:|---:|---|---:|---:|---|---|---|---|---|---:|---:|---:|')
    for name in METHODS:
        m = s.get(name)
        if not m:
            continue
        print('| %s | %s | %s | %s | %s | %s / %s | %s | %s | %d / %d / %d | %s / %s | %s + %s of %s + %s '
              '| %s / %s | %s / %s | %s | %s | %s |' % (
                  name, f(m['map50'], '%.1f'), f(m['map75'], '%.1f'), f(m['map50_95'], '%.1f'),
                  f(m.get('map50_95_mask'), '%.1f'), f(m['precision50'], '%.3f'),
                  f(m['recall50'], '%.3f'), f(m['adds_auc'], '%.1f'),
                  f(m['adds_under_1cm'], '%.3f'), m['final_objects'], m['final_matched'],
                  m['final_true_objects'], f(m['lifecycle_lost'], '%d'),
                  f(m['lifecycle_flip_flops'], '%d'), f(m['surviving_phantoms'], '%d'),
                  f(m['surviving_swaps'], '%d'), f(m['persistent_phantoms'], '%d'),
                  f(m['persistent_swaps'], '%d'), f(m['ate_mm'], '%.1f'),
                  f(m['odometry_ate_mm'], '%.1f'), f(m['contact_f1'], '%.3f'),
                  f(m['contact_pair_f1'], '%.3f'), f(m['penetration_mean_mm'], '%.2f'),
                  f(m['ms_per_keyframe_p95'], '%.1f'), f(m['realtime_factor'], '%.3f')))
    g = s.get('GeoFusion', {})
    kinds = []
    for kind in ('support', 'leaning', 'side'):
        kinds.append('%s P %s / R %s / F1 %s (%s correct of %s found, %s true)' % (
            kind, f(g.get('contact_%s_precision' % kind), '%.3f'),
            f(g.get('contact_%s_recall' % kind), '%.3f'), f(g.get('contact_%s_f1' % kind), '%.3f'),
            g.get('contact_%s_correct' % kind), g.get('contact_%s_estimated' % kind),
            g.get('contact_%s_true' % kind)))
    print("\nGeoFusion's contacts per kind (pair and kind): " + ', '.join(kinds))
    if g.get('removals'):
        print('\nChanged scene: GeoFusion %s removals, latency mean %s / max %s keyframes, %s ghosts' % (
            g['removals'], f(g.get('removal_latency_mean'), '%.1f'),
            f(g.get('removal_latency_max'), '%d'), g.get('removal_ghosts')))
    met = sum(1 for t in s.get('targets', []) if t['met'])
    print('\nTargets (%d of %d met):\n\n| target | measured | result |\n|---|---|---|' %
          (met, len(s.get('targets', []))))
    for t in s.get('targets', []):
        print('| %s | %s | %s |' % (t['target'], t['measured'], t['status']))
    scenes = s.get('scenes', {})
    ate = ['%s %s / %s' % (sc, f(v.get('GeoFusion', {}).get('ate_mm'), '%.1f'),
                            f(v.get('GeoFusion', {}).get('odometry_ate_mm'), '%.1f'))
           for sc, v in sorted(scenes.items())]
    print('\nATE per scene, GeoFusion / odometry (mm): ' + ', '.join(ate))


if __name__ == '__main__':
    main()
