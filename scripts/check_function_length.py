#!/usr/bin/env python3
"""Every function body in the package at most MAX lines (docs/architecture.md: a function reads like
one step of the paper's algorithm). A small brace scanner: comments, strings and character literals
are blanked, namespaces and extern "C" blocks are transparent, a body is a '{' after a ')' (with
qualifiers such as const/override/noexcept or a constructor's initialiser list between) at
namespace or class level. Prints the longest functions; exit 1 when one is over the limit.

  check_function_length.py [--max N] [--top K] [--self-test] DIR...
"""
import argparse
import os
import re
import sys

MAX_LINES = 120


def blank_comments_and_strings(text):
    """Replaces comments, string and char literals by spaces, keeping newlines (line numbers)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = ")" + m.group(1) + '"'
            j = text.find(end, i + m.end())
            j = n if j < 0 else j + len(end)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum():  # digit separator 1'000
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def blank_preprocessor(text):
    lines = text.split("\n")
    out, cont = [], False
    for line in lines:
        if cont or line.lstrip().startswith("#"):
            cont = line.rstrip().endswith("\\")
            out.append("")
        else:
            out.append(line)
    return "\n".join(out)


FUNC_TAIL = re.compile(
    r"\)\s*(const|override|final|noexcept(\s*\([^()]*\))?|mutable|->\s*[\w:<>,\s\*&]+|\s)*$")
INIT_LIST = re.compile(r"\)\s*:\s*[\w:]+\s*[({][\s\S]*$")


def functions(text):
    """(name, first line, number of lines) of every function body at namespace or class level."""
    code = blank_preprocessor(blank_comments_and_strings(text))
    stack = []  # entries: 'ns' (transparent), 'class', 'func', 'other'
    result = []
    stmt_start = 0
    for i, c in enumerate(code):
        if c == "{":
            head = code[stmt_start:i]
            in_func = any(k == "func" for k, _, _ in stack)
            kind = "other"
            h = head.strip()
            if not in_func and re.search(r"\)\s*:(?!:)[\s\S]*[\w>]$", h):
                stack.append(("init", i, ""))  # a brace initialiser in a constructor's list
                continue
            if not in_func:
                if re.search(r"\bnamespace\b[\w\s:]*$", h) or re.search(r'extern\s*$', h):
                    kind = "ns"
                elif re.search(r"\b(class|struct|union|enum)\b[^;()]*$", h):
                    kind = "class"
                elif FUNC_TAIL.search(h) or (INIT_LIST.search(h) and "(" in h):
                    kind = "func"
            name = ""
            if kind == "func":
                m = re.search(r"([~\w:]+(?:operator\s*[^\s(]+)?)\s*\(", head)
                name = m.group(1) if m else "?"
            stack.append((kind, i, name))
            stmt_start = i + 1
        elif c == "}":
            if stack:
                kind, start, name = stack.pop()
                if kind == "init":
                    continue
                if kind == "func":
                    first = code.count("\n", 0, start) + 1
                    last = code.count("\n", 0, i) + 1
                    result.append((name, first, last - first + 1))
            stmt_start = i + 1
        elif c == ";":
            stmt_start = i + 1
    return result


def self_test():
    src = """
namespace a {
// void fake() {
int f(int x) {
  auto l = [](int y) { return y; };
  if (x) { return l(x); }
  return 0;
}
struct S {
  S() : v_{1} {
    v_ = 2;
  }
  int g() const {
    return "}{"[0];
  }
  int v_;
};
}  // namespace a
"""
    found = {name: lines for name, _, lines in functions(src)}
    assert found.get("f") == 5, found
    assert found.get("S") == 3, found
    assert found.get("g") == 3, found
    assert "l" not in found and "fake" not in found, found
    print("check_function_length self-test passed")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--max", type=int, default=MAX_LINES)
    ap.add_argument("--top", type=int, default=10)
    ap.add_argument("--self-test", action="store_true")
    ap.add_argument("dirs", nargs="*")
    args = ap.parse_args()
    if args.self_test:
        self_test()
        if not args.dirs:
            return 0
    rows = []
    for d in args.dirs:
        for root, _, files in os.walk(d):
            for f in files:
                if f.endswith((".cpp", ".h")):
                    path = os.path.join(root, f)
                    with open(path, encoding="utf-8", errors="replace") as fh:
                        for name, line, n in functions(fh.read()):
                            rows.append((n, path, line, name))
    rows.sort(reverse=True)
    for n, path, line, name in rows[: args.top]:
        print(f"{n:5d}  {path}:{line}  {name}")
    over = [r for r in rows if r[0] > args.max]
    if over:
        print(f"{len(over)} function(s) over {args.max} lines", file=sys.stderr)
        return 1
    print(f"{len(rows)} functions, the longest {rows[0][0] if rows else 0} lines (limit {args.max})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
