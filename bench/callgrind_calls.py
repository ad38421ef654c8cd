#!/usr/bin/env python3
"""Instructions per call of the functions whose name matches REGEX, from a
callgrind output file (inclusive cost summed over every call site):

    bench/callgrind_calls.py callgrind.out 'Predict|Update'
"""
import re
import sys


def main(path, pattern):
    names = {}  # id -> name (callgrind name compression)
    rx = re.compile(pattern)
    totals = {}  # name -> [calls, inclusive Ir]
    pending = None  # (name, calls) waiting for its cost line
    with open(path, errors="replace") as f:
        for line in f:
            line = line.rstrip("\n")
            m = re.match(r"^c?fn=\((\d+)\)(?: (.*))?$", line)
            if m:
                fid, name = m.group(1), m.group(2)
                if name is not None:
                    names[fid] = name
                if line.startswith("cfn="):
                    pending = [names.get(fid, fid), None]
                continue
            if line.startswith("calls=") and pending is not None:
                pending[1] = int(line.split("=")[1].split()[0])
                continue
            if pending is not None and pending[1] is not None and line and line[0] in "0123456789+-*":
                parts = line.split()
                cost = int(parts[1]) if len(parts) > 1 else 0
                name = pending[0]
                if rx.search(name):
                    t = totals.setdefault(name, [0, 0])
                    t[0] += pending[1]
                    t[1] += cost
                pending = None
    for name, (calls, cost) in sorted(totals.items(), key=lambda kv: -kv[1][1]):
        short = re.sub(r"\(.*", "", name)[-90:]
        print(f"{cost / max(calls, 1):10.0f} Ir/call  {calls:9d} calls  {short}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
