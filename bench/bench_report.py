"""Renders docs/BENCHMARKS.md from docs/figures/bench_results.json (see bench.py)."""
import json
from pathlib import Path


def sim_rows(bindir, quick):
    return {}


def render(store, path: Path):
    path.write_text("# Benchmarks\n\n```\n" + json.dumps({k: v["agg"] for k, v in store["rows"].items()}, indent=1) + "\n```\n")
