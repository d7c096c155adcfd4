#!/usr/bin/python3
"""Plots a soak_benchmark CSV (issue 22): time a keyframe by stage against the keyframe number
(rolling means stacked, the rolling p95 of the total on top) and resident memory against the
keyframe number. Writes <out>/soak_time.png and <out>/soak_memory.png.

    plot_soak.py soak.csv OUT_DIR [--window 100]
"""
import argparse
import csv
import os
import sys

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402

STAGES = [('consistency_ms', 'consistency + refinement'), ('association_ms', 'association'),
          ('lifecycle_ms', 'lifecycle'), ('stage_one_ms', 'stage I'), ('relations_ms', 'relations'),
          ('stage_two_ms', 'stage II')]


def rolling(values, window, statistic):
    out = numpy.empty(len(values))
    for i in range(len(values)):
        out[i] = statistic(values[max(0, i - window + 1):i + 1])
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('csv')
    parser.add_argument('out_dir')
    parser.add_argument('--window', type=int, default=100)
    args = parser.parse_args()
    with open(args.csv) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        print('plot_soak: %s has no keyframes' % args.csv, file=sys.stderr)
        return 1
    os.makedirs(args.out_dir, exist_ok=True)
    k = numpy.array([int(r['keyframe']) for r in rows])
    column = {key: numpy.array([float(r[key]) for r in rows])
              for key in [s for s, _ in STAGES] + ['total_ms', 'rss_mb', 'objects']}
    w = args.window

    fig, ax = plt.subplots(figsize=(10, 5))
    stacked = [rolling(column[key], w, numpy.mean) for key, _ in STAGES]
    ax.stackplot(k, stacked, labels=[label + ' (mean)' for _, label in STAGES], alpha=0.8)
    ax.plot(k, rolling(column['total_ms'], w, lambda v: numpy.percentile(v, 95)), 'k-', lw=1.5,
            label='total, p95')
    ax.set_xlabel('keyframe')
    ax.set_ylabel('ms a keyframe (rolling over %d keyframes)' % w)
    ax.set_title('GeoFusion soak: time a keyframe by stage')
    ax.grid(alpha=0.3)
    twin = ax.twinx()
    twin.plot(k, column['objects'], color='grey', lw=0.8, ls='--', label='objects in the map')
    twin.set_ylabel('objects in the map')
    lines, labels = ax.get_legend_handles_labels()
    l2, lab2 = twin.get_legend_handles_labels()
    ax.legend(lines + l2, labels + lab2, loc='upper left', fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out_dir, 'soak_time.png'), dpi=110)

    fig, ax = plt.subplots(figsize=(10, 4))
    ax.plot(k, column['rss_mb'], 'b-')
    ax.set_xlabel('keyframe')
    ax.set_ylabel('resident memory, MB')
    ax.set_title('GeoFusion soak: memory (rendering and estimator in one process)')
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out_dir, 'soak_memory.png'), dpi=110)
    print('plot_soak: %s/soak_time.png, %s/soak_memory.png' % (args.out_dir, args.out_dir))
    return 0


if __name__ == '__main__':
    sys.exit(main())
