#!/usr/bin/env python3
"""Instructions per call of the functions whose name matches REGEX, from a
callgrind output file (inclusive cost summed over every call site):

    bench/callgrind_calls.py callgrind.out 'Predict|Update'

With a third argument PER, one number: the inclusive Ir of REGEX's calls
over the number of calls of PER, e.g. Ir per filter step of a bench row
(its loop function over its Predict calls; Google Benchmark's trial runs
count in both, so nothing depends on how many iterations it chose):

    bench/callgrind_calls.py callgrind.out 'FilterStep<' '::Predict\('
"""
import re
import sys


def Callees(path):
    """name -> [calls, inclusive Ir], summed over every call site."""
    names = {}  # id -> name (callgrind name compression)
    totals = {}
    pending = None  # [name, calls] waiting for its cost line
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
                t = totals.setdefault(pending[0], [0, 0])
                t[0] += pending[1]
                t[1] += int(parts[1]) if len(parts) > 1 else 0
                pending = None
    return totals


def main(path, pattern, per=None):
    callees = Callees(path)
    rx = re.compile(pattern)
    totals = {name: t for name, t in callees.items() if rx.search(name)}
    if per is not None:
        rx_per = re.compile(per)
        per_calls = sum(calls for name, (calls, _) in callees.items() if rx_per.search(name))
        cost = sum(c for _, c in totals.values())
        print(f"{cost / max(per_calls, 1):.1f} Ir per call of {per} ({per_calls} calls)")
        return
    for name, (calls, cost) in sorted(totals.items(), key=lambda kv: -kv[1][1]):
        short = re.sub(r"\(.*", "", name)[-90:]
        print(f"{cost / max(calls, 1):10.0f} Ir/call  {calls:9d} calls  {short}")


if __name__ == "__main__":
    main(*sys.argv[1:4])
