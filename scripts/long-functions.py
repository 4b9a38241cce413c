#!/usr/bin/env python3
"""Functions longer than a limit (150 lines by default) in the workspace's production code, longest
first: test modules (`#[cfg(test)] mod ...`), `tests/` folders and benchmarks are left out. A function
counts from its `fn` line to its closing brace. Each says whether its doc comment gives the reason
for its length (a sentence "Long because ..."), and the last line counts those that do not.

    python3 scripts/long-functions.py [LIMIT]
"""
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FOLDERS = ["core", "frame", "scene", "host-cpu", "host-vulkan", "cli", "gpu-kernel"]
FN = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:const\s+)?(?:unsafe\s+)?fn\s+(\w+)")


def functions(path):
    lines = open(path, encoding="utf-8").read().split("\n")
    out = []
    i = 0
    while i < len(lines):
        if re.match(r"\s*#\[cfg\(test\)\]", lines[i]) and i + 1 < len(lines) and re.match(
            r"\s*(pub\s+)?mod\s+\w+\s*\{", lines[i + 1]
        ):
            break  # the test module runs to the end of the file
        m = FN.match(lines[i])
        if m:
            depth, started, j = 0, False, i
            while j < len(lines):
                code = re.sub(r"//.*", "", lines[j])
                code = re.sub(r'"(\\.|[^"\\])*"', '""', code)
                code = re.sub(r"'(\\.|[^'\\])'", "''", code)
                depth += code.count("{") - code.count("}")
                started |= "{" in code
                if started and depth <= 0:
                    break
                if not started and code.rstrip().endswith(";"):
                    break  # a declaration without a body
                j += 1
            k = i - 1
            while k >= 0 and (lines[k].strip().startswith("///") or lines[k].strip().startswith("#[")):
                k -= 1
            reason = any("Long because" in l for l in lines[k + 1 : i])
            out.append((j - i + 1, m.group(1), i + 1, reason))
            i = j + 1 if started else i + 1
            continue
        i += 1
    return out


def main():
    limit = int(sys.argv[1]) if len(sys.argv) > 1 else 150
    rows = []
    for folder in FOLDERS:
        for dirpath, _, names in os.walk(os.path.join(ROOT, folder, "src")):
            for n in names:
                if n.endswith(".rs"):
                    p = os.path.join(dirpath, n)
                    for length, name, line, reason in functions(p):
                        if length > limit:
                            rows.append((length, f"{os.path.relpath(p, ROOT)}:{line}", name, reason))
    for length, where, name, reason in sorted(rows, reverse=True):
        print(f"{length:5d}  {name}  {where}{'' if reason else '  (no reason given)'}")
    without = sum(1 for r in rows if not r[3])
    print(f"{len(rows)} functions over {limit} lines, {without} without a reason in their doc comment")


if __name__ == "__main__":
    main()
