#!/usr/bin/python3
"""Counts the operations of the simulator's AVX-512 pair pass in its compiled inner loop.

The benchmark's bound for the simulator (bench_report.SIM_FMA_PER_PAIR) is the pair pass's multiply-adds
and multiplies per pair over the core's peak multiply-add rate; this script reads that count from the
object file the build made (objdump -d), so the report's figure is of the loop that runs:

usage: bench/sim_loop_count.py [OBJECT] [--check]

OBJECT defaults to build/common/core/CMakeFiles/shapeform_core.dir/batch_avx512.cpp.o. A group of two rows
goes through each tile of agents j in three sweeps (common/core/batch_kernel.hpp, PairKernel::rows with
AnyBeta), each a loop (a backward branch) with no scalar arithmetic, found as the shortest loop that has:
the distances: four vector compares (two rows' nearest-neighbour bookkeeping) and no vgetmantpd or
vscalefpd; the weights' heads: two vgetmantpd (two vectors of weights) and no vscalefpd; the tails and
sums: two vscalefpd (two rows) and no vgetmantpd. Each covers 16 pairs. Prints the three loops' vector
instructions, their multiply-adds and multiplies (vfmadd*, vfnmadd*, vfmsub*, vfnmsub*, vmulpd), and the
multiply-adds per pair they make (8 lanes each). With --check the exit status is 1 unless the count per
pair is bench_report.SIM_FMA_PER_PAIR.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_OBJECT = ROOT / "build/common/core/CMakeFiles/shapeform_core.dir/batch_avx512.cpp.o"
ROWS, LANES = 2, 8  # PairKernel::kRows, the AVX-512 vector's doubles: pairs per iteration = ROWS * LANES
FMA = re.compile(r"^(vfn?madd|vfn?msub)\d{3}pd$|^vmulpd$")


def instructions(obj: Path) -> list[tuple[int, str, str]]:
    try:
        text = subprocess.run(["objdump", "-d", "--no-show-raw-insn", str(obj)], check=True,
                              capture_output=True, text=True).stdout
    except FileNotFoundError:
        sys.exit("sim_loop_count: objdump not found (Debian package binutils)")
    except subprocess.CalledProcessError as e:
        sys.exit(f"sim_loop_count: objdump could not read {obj}: {e.stderr.strip()}")
    out = []
    for line in text.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s+(\S+)\s*(.*)", line)
        if m:
            out.append((int(m.group(1), 16), m.group(2), m.group(3)))
    return out


CMP = re.compile(r"^vcmp\w*pd$")
SWEEPS = {  # name: (what the loop must hold, what it must not)
    "distances": (lambda c: sum(n for o, n in c.items() if CMP.match(o)) == 2 * ROWS,
                  lambda c: c["vgetmantpd"] or c["vscalefpd"]),
    "heads": (lambda c: c["vgetmantpd"] == 2, lambda c: c["vscalefpd"]),
    "tails": (lambda c: c["vscalefpd"] == ROWS, lambda c: c["vgetmantpd"]),
}


def sweep_loops(ins: list[tuple[int, str, str]]) -> dict[str, list[str]]:
    """The mnemonics of each sweep's loop (see the module's doc) that was found."""
    index = {a: i for i, (a, _, _) in enumerate(ins)}
    best: dict[str, list[str]] = {}
    for i, (a, op, args) in enumerate(ins):
        m = re.match(r"([0-9a-f]+)\b", args)
        if not op.startswith("j") or not m:
            continue
        target = int(m.group(1), 16)
        if target >= a or target not in index:
            continue
        body = [o for _, o, _ in ins[index[target]:i + 1]]
        if any(o.endswith("sd") and o != "vbroadcastsd" for o in body):
            continue
        c = Counter(body)
        for name, (holds, lacks) in SWEEPS.items():
            if holds(c) and not lacks(c) and (name not in best or len(body) < len(best[name])):
                best[name] = body
    return best


def main() -> int:
    ap = argparse.ArgumentParser(description="Operations of the simulator's AVX-512 pair pass per pair, "
                                 "counted in its compiled inner loop (objdump).")
    ap.add_argument("object", nargs="?", type=Path, default=DEFAULT_OBJECT,
                    help="batch_avx512.cpp's object file (default: %(default)s)")
    ap.add_argument("--check", action="store_true",
                    help="exit 1 unless the count per pair is bench_report.SIM_FMA_PER_PAIR")
    args = ap.parse_args()
    if not args.object.is_file():
        sys.exit(f"sim_loop_count: no object file {args.object} (build shapeform_core first, or give the path "
                 "of batch_avx512.cpp.o)")
    loops = sweep_loops(instructions(args.object))
    missing = [name for name in SWEEPS if name not in loops]
    if missing:
        sys.exit(f"sim_loop_count: no loop of the {', '.join(missing)} sweep in {args.object}: has PairKernel's "
                 "pass changed? (update this script and bench_report.SIM_FMA_PER_PAIR)")
    pairs = ROWS * LANES
    fma = vec = 0
    for name in SWEEPS:
        f = sum(1 for o in loops[name] if FMA.match(o))
        v = sum(1 for o in loops[name] if o.startswith("v"))
        print(f"{name} sweep: {len(loops[name])} instructions, {v} vector, {f} vector multiply-adds or multiplies "
              f"per {pairs} pairs")
        fma, vec = fma + f, vec + v
    per_pair = fma * LANES / pairs  # each vector instruction does LANES pairs' operation
    print(f"in all: {vec} vector instructions, {fma} multiply-adds or multiplies per {pairs} pairs: "
          f"{per_pair:g} multiply-adds or multiplies per pair")
    if args.check:
        sys.path.insert(0, str(ROOT / "bench"))
        sys.dont_write_bytecode = True
        from bench_report import SIM_FMA_PER_PAIR  # noqa: E402
        if per_pair != SIM_FMA_PER_PAIR:
            print(f"sim_loop_count: bench_report.SIM_FMA_PER_PAIR is {SIM_FMA_PER_PAIR}, the compiled loop has "
                  f"{per_pair:g}: set it to the loop's count", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
