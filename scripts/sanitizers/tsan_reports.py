#!/usr/bin/env python3
"""ThreadSanitizer's report files, named and sorted (scripts/test_sanitizer.sh thread).

gcc's TSan runtime leaves some frames unnamed ("#3 <null> <null> (libgeofusion_ros.so+0x1f2e3)"):
it did in both of the package's first runs, for frames in the instrumented nodelet libraries and
in Debian's roscpp, and its suppressions, which match names, then miss them. This names each such
frame with addr2line (binutils, from the module's debug information or its symbol table), then
applies scripts/sanitizers/tsan.supp as TSan does: a report is suppressed when a pattern of its
type (race:, deadlock:, thread:, mutex:, signal:) matches the function, file or module of any
frame of any of its stacks ('*' any characters, '^' and '$' anchors).

Writes each report, named, to OUT_DIR (one file per input file) and prints, per report file, how
many reports are left and which suppression took the others. Exit code: 0 when no report is left,
1 otherwise, 2 for bad arguments.

TSan prints a module by its file name only ("libgeofusion_ros.so"): it is looked up in the folders
of $TSAN_REPORTS_SEARCH (':'-separated, searched recursively, the first match), by default the
workspace's devel/lib and the system's library folders.

usage: tsan_reports.py SUPPRESSIONS OUT_DIR REPORT_FILE...
"""
import os
import re
import subprocess
import sys
from collections import Counter

# A frame: its function (a C++ signature may hold spaces), location and module+offset.
FRAME = re.compile(r'^(\s*#\d+ )(.+) (\S+) \(([^()\s]+)\+(0x[0-9a-f]+)\)\s*$')
TYPES = {'data race': 'race', 'lock-order-inversion': 'deadlock', 'thread leak': 'thread',
         'destroy of a locked mutex': 'mutex', 'use of an invalid mutex': 'mutex',
         'unlock of an unlocked mutex': 'mutex', 'signal-unsafe call': 'signal',
         'signal handler spoils errno': 'signal', 'heap-use-after-free': 'race',
         'data race on vptr': 'race'}


def read_suppressions(path):
    rules = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith('#') or ':' not in line:
                continue
            kind, pattern = line.split(':', 1)
            rules.append((kind.strip(), pattern.strip()))
    return rules


def matches(pattern, text):
    """TSan's TemplateMatch: '*' any characters, '^' start, '$' end, else a substring."""
    if not text:
        return False
    regex = ''.join('.*' if c == '*' else re.escape(c) for c in pattern.strip('^$'))
    if pattern.startswith('^'):
        regex = '^' + regex
    if pattern.endswith('$'):
        regex += '$'
    return re.search(regex, text) is not None


class Namer:
    """addr2line per module, each address asked once."""

    def __init__(self, search):
        self.cache = {}
        self.search = [d for d in search if os.path.isdir(d)]
        self.paths = None

    def path(self, module):
        if os.path.isfile(module):
            return module
        if self.paths is None:
            self.paths = {}
            for top in self.search:
                for folder, _, files in os.walk(top):
                    for name in files:
                        self.paths.setdefault(name, os.path.join(folder, name))
        return self.paths.get(os.path.basename(module), '')

    def name(self, module_name, offset):
        key = (module_name, offset)
        if key not in self.cache:
            self.cache[key] = ('<null>', '<null>')
            module = self.path(module_name)
            if module:
                try:
                    out = subprocess.run(['addr2line', '-C', '-f', '-e', module, offset],
                                         stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                         universal_newlines=True, timeout=60).stdout.split('\n')
                    if len(out) >= 2 and out[0] != '??':
                        self.cache[key] = (out[0], out[1] if not out[1].startswith('??') else '<null>')
                except (OSError, subprocess.TimeoutExpired):
                    pass
        return self.cache[key]


def split_reports(text):
    """The reports of one file: each from its 'WARNING: ThreadSanitizer:' line to its '====' line."""
    reports, current = [], None
    for line in text.split('\n'):
        if 'WARNING: ThreadSanitizer:' in line:
            current = [line]
        elif current is not None:
            current.append(line)
            if line.startswith('=================='):
                reports.append(current)
                current = None
    if current:
        reports.append(current)
    return reports


def report_type(first_line):
    what = first_line.split('WARNING: ThreadSanitizer:', 1)[1].strip()
    for name, kind in TYPES.items():
        if what.startswith(name):
            return kind
    return 'race'


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    rules = read_suppressions(argv[0])
    out_dir = argv[1]
    os.makedirs(out_dir, exist_ok=True)
    default = [os.path.join(os.environ.get('GEOFUSION_WS', ''), 'devel', 'lib'),
               '/usr/lib/x86_64-linux-gnu', '/lib/x86_64-linux-gnu', '/usr/lib']
    namer = Namer(os.environ.get('TSAN_REPORTS_SEARCH', ':'.join(default)).split(':'))
    left_total, taken = 0, Counter()
    for path in argv[2:]:
        with open(path, errors='replace') as f:
            text = f.read()
        kept = []
        for report in split_reports(text):
            kind = report_type(report[0])
            named, frames = [], []
            for line in report:
                m = FRAME.match(line)
                if m:
                    prefix, function, location, module, offset = m.groups()
                    if function == '<null>':
                        function, location = namer.name(module, offset)
                        line = '%s%s %s (%s+%s)' % (prefix, function, location, module, offset)
                    frames.append((function, location, module))
                named.append(line)
            rule = next((r for r in rules if r[0] == kind and any(
                matches(r[1], f) or matches(r[1], loc) or matches(r[1], mod)
                for f, loc, mod in frames)), None)
            if rule:
                taken['%s:%s' % rule] += 1
            else:
                kept.append('\n'.join(named))
        left_total += len(kept)
        with open(os.path.join(out_dir, os.path.basename(path)), 'w') as f:
            f.write('\n\n'.join(kept))
        print('%s: %d report(s) left' % (os.path.basename(path), len(kept)))
    for rule, count in taken.most_common():
        print('  suppressed once named: %5d  %s' % (count, rule))
    print('%d report(s) left in %d file(s)' % (left_total, len(argv) - 2))
    return 0 if left_total == 0 else 1


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
