#!/usr/bin/env python3
"""Instruction counts of a callgrind profile by inline call chain.

The tracer's hot code is one function (`render_tile_avx2`) with everything
inlined into it, so `callgrind_annotate` can only sort its instructions by
source line. This script reads the per-instruction counts of a profile taken
with `--dump-instr=yes`, asks `addr2line -i` for each address's chain of
inlined frames, and sums the counts by the chain's first DEPTH frames of
epsm's own code (outermost first).

    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=cg.out \
        target/release/epsm bench render scenes/cornell-box.toml --max-depth 8 --spp 8 --repeats 1
    scripts/callgrind-inline.py cg.out target/release/epsm --depth 5 --per 262144
    scripts/callgrind-inline.py cg.out target/release/epsm --depth 8 --within next_event

--function picks the compiled function (default render_tile_avx2); --within
keeps the chains that pass through a frame of that name; --per divides the
counts (by the samples rendered, to read instructions per sample: `bench
render` renders width x height x spp samples on each of 1 and 2 threads);
--lines sums by the innermost frame and its source line instead.
"""

import argparse
import collections
import re
import subprocess


def instruction_costs(path, function):
    """Self cost per instruction address of the functions named like `function`."""
    names, costs = {}, collections.Counter()
    fn, last, after_call = None, 0, False
    with open(path) as f:
        for line in f:
            # Names are given once, at a function's first `fn=` or `cfn=`.
            m = re.match(r"(c?)fn=\((\d+)\)(?: (.*))?", line)
            if m:
                if m.group(3):
                    names[m.group(2)] = m.group(3).strip()
                if not m.group(1):
                    fn = names.get(m.group(2))
                continue
            if line.startswith("calls="):
                after_call = True
                continue
            if not line or line[0] not in "0123456789+-*":
                continue
            parts = line.split()
            a = parts[0]
            if a.startswith("0x"):
                addr = int(a, 16)
            elif a[0] == "+":
                addr = last + int(a[1:])
            elif a[0] == "-":
                addr = last - int(a[1:])
            elif a == "*":
                addr = last
            else:
                addr = int(a)
            last = addr
            if after_call:
                # The line after `calls=` is the call's inclusive cost.
                after_call = False
                continue
            if len(parts) >= 3 and fn and function in fn:
                costs[addr] += int(parts[2])
    return costs


def inline_chains(binary, addresses):
    """Inlined frames `(function, file:line)` per address, innermost first."""
    out = subprocess.run(
        ["addr2line", "-e", binary, "-i", "-f", "-C", "-a"],
        input="\n".join(hex(a) for a in addresses),
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split("\n")
    chains, current, i = {}, None, 0
    while i < len(out):
        line = out[i]
        if line.startswith("0x"):
            current = int(line, 16)
            chains[current] = []
            i += 1
        elif line and current is not None:
            chains[current].append((line, out[i + 1] if i + 1 < len(out) else ""))
            i += 2
        else:
            i += 1
    return chains


def short(function):
    """The last path segment of a demangled name, generics removed."""
    while "<" in function:
        stripped = re.sub(r"<[^<>]*>", "", function)
        if stripped == function:
            break
        function = stripped
    return function.split("::")[-1]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("profile")
    p.add_argument("binary")
    p.add_argument("--function", default="render_tile_avx2")
    p.add_argument("--depth", type=int, default=5)
    p.add_argument("--within", default="")
    p.add_argument("--per", type=float, default=1.0)
    p.add_argument("--lines", action="store_true")
    p.add_argument("--top", type=int, default=30)
    args = p.parse_args()

    costs = instruction_costs(args.profile, args.function)
    chains = inline_chains(args.binary, sorted(costs))
    total = sum(costs.values())
    sums = collections.Counter()
    for addr, cost in costs.items():
        frames = chains.get(addr, [])
        ours = [short(f) for f, loc in reversed(frames) if "epsm" in f or "/crates/" in loc]
        if args.within and args.within not in ours:
            continue
        if args.lines and frames:
            function, loc = frames[0]
            key = f"{short(function)} {loc.split('/src/')[-1]}"
        else:
            key = " > ".join(ours[: args.depth])
        sums[key] += cost
    print(f"{total / args.per:.0f} instructions in {args.function} (per {args.per:g})")
    for key, cost in sums.most_common(args.top):
        print(f"{100 * cost / total:6.2f} % {cost / args.per:8.0f}  {key}")


if __name__ == "__main__":
    main()
