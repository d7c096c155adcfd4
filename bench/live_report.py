"""The live benchmark's summary (make live-bench): every run_*.json of a folder into summary.json,
a markdown table on stdout (docs/BENCHMARK.md's "Live" section) and latency.png."""
import argparse
import glob
import json
import os

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402


def fmt(x, digits=0):
    return '-' if x is None else ('%.*f' % (digits, x))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument('--dir', required=True)
    a = ap.parse_args()
    runs = []
    for path in sorted(glob.glob(os.path.join(a.dir, 'run_*.json'))):
        with open(path) as f:
            r = json.load(f)
        r['name'] = os.path.basename(path)[4:-5]
        runs.append(r)
    with open(os.path.join(a.dir, 'summary.json'), 'w') as f:
        json.dump([{k: v for k, v in r.items() if k != 'latency_series_ms'} for r in runs], f,
                  indent=1)
    print('| run | frames sent | maps | frames after the first map without one | latency p50 / p95 '
          '/ max ms | after the first map p95 / max ms | first map ms | from the detections p50 / '
          'p95 / max ms | TF p50 / p95 / max ms | dropped (estimator, by reason) | background ms '
          'a keyframe amortised / passed over | manager CPU % |')
    print('|' + '---|' * 12)
    for r in runs:
        d = r.get('diagnostics', {})
        drops = ', '.join('%s %s' % (k.split(': ', 1)[1], v) for k, v in sorted(d.items())
                          if k.startswith('frames dropped: ') and v not in ('0', 0)) or 'none'
        lat, after, tf = r['latency_ms'], r['latency_ms_after_first'], r['tf_latency_ms']
        own = r.get('own_latency_ms', {'p50': None, 'p95': None, 'max': None})
        amortised = d.get('background ms: a keyframe (amortised)')
        print('| %s | %d | %d | %d | %s / %s / %s | %s / %s | %s | %s / %s / %s | %s / %s / %s | %s '
              '| %s / %s | %s |'
              % (r['name'], r['frames_sent'], r['maps_received'],
                 r['frames_without_map_after_first'], fmt(lat['p50']), fmt(lat['p95']),
                 fmt(lat['max']), fmt(after['p95']), fmt(after['max']),
                 fmt(r['first_map_latency_ms']), fmt(own['p50']), fmt(own['p95']),
                 fmt(own['max']), fmt(tf['p50']), fmt(tf['p95']), fmt(tf['max']),
                 drops, fmt(float(amortised), 1) if amortised else '-',
                 d.get('background keyframes passed over (camera still)', '-'),
                 fmt(r.get('manager_cpu_percent'))))
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for r in runs:
        ax.plot(r['latency_series_ms'], label=r['name'], lw=1)
    ax.set_xlabel('map (keyframe) number')
    ax.set_ylabel('latency, frame to ObjectMap (ms)')
    ax.set_yscale('log')
    ax.axhline(150, color='k', ls='--', lw=0.8)
    ax.axhline(300, color='k', ls=':', lw=0.8)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(a.dir, 'latency.png'), dpi=100)


if __name__ == '__main__':
    main()
