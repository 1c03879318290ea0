#!/usr/bin/python3
"""Derives a scenario's expect bounds from many seeds, or checks them on held-out seeds.

The rule (docs/results.md, "How the bounds are set"): every bound is the worst value over the
derivation seeds (1-30 by default) with a 30 % margin: an upper bound is max + 0.3 |max|, a lower
bound min - 0.3 |min|; `mpc_failures_max` is the worst count (failures are whole updates);
`crashed: false` only when no derivation seed crashed. A regression that makes every run 50 %
worse therefore fails at least on the worst seed, and seeds beyond the derivation set (31-40)
test the bound on cases it was not fitted on.

  scenario_bounds.py SCENARIO.yaml [--seeds 1-30] [--hpa build/bin/hpa] [--write]
  scenario_bounds.py --check SCENARIO.yaml... [--seeds 1-40 | --held-out N | --unseen 100
                                                [--unseen-from 100001]]

Derive prints the new expect block with the measured ranges (and --write puts it into the file,
replacing the comment block before `expect:` and the block itself). --check runs the seeds and
lists every seed whose run fails the file's bounds (exit 1 if any; with --unseen, if any file
passes on fewer than --min-pass of them). --unseen-from moves the unseen seeds: a file re-derived
after failures on 100001-100100 were seen is checked on those and on a fresh 100101-100200.
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

import yaml


def parse_seeds(text):
    lo, _, hi = text.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def expect_keys(hpa):
    """key -> (metric path, 'max' | 'min' | 'eq', per-axis) from `hpa schema expect`."""
    out = subprocess.run([hpa, "schema", "expect"], check=True, capture_output=True,
                         text=True).stdout
    keys = {}
    for line in out.splitlines():
        m = re.match(r"\| `([a-z_]+)` \| `([A-Za-z_.]+)` \| ([^|]+) \|", line)
        if not m:
            continue
        key, metric, passes = m.group(1), m.group(2), m.group(3)
        kind = "eq" if "==" in passes else ("max" if "<=" in passes else "min")
        keys[key] = (metric, kind, "per axis" in passes)
    return keys


def run_seeds(hpa, scenario, seeds, out, jobs):
    def one(seed):
        d = os.path.join(out, f"seed{seed}")
        subprocess.run([hpa, "run", scenario, "--seed", str(seed), "--out", d, "--quiet"],
                       capture_output=True)
        path = os.path.join(d, "metrics.json")
        if not os.path.exists(path):
            sys.exit(f"{scenario} seed {seed}: no metrics.json written")
        return seed, json.load(open(path))
    with ThreadPoolExecutor(jobs) as pool:
        return dict(pool.map(one, seeds))


def read(metrics, path):
    """The metric at a dotted path; through a list (a team's vehicles), the largest of its
    entries' values, as the expect key checks it."""
    v = metrics
    parts = path.split(".")
    for i, part in enumerate(parts):
        if isinstance(v, list):
            values = [read(entry, ".".join(parts[i:])) for entry in v]
            values = [x for x in values if x is not None]
            return max(values) if values else None
        v = v.get(part) if isinstance(v, dict) else None
    return v


def fmt(x):
    return f"{x:.3g}" if abs(x) < 1e3 else f"{x:.0f}"


def rounded(x, kind):
    """x rounded outward (up for an upper bound, down for a lower one) to 3 significant digits."""
    if x == 0:
        return 0.0
    scale = 10 ** (math.floor(math.log10(abs(x))) - 2)
    steps = x / scale
    # a value already on the grid (0.7 computed as 0.69999...) stays where it is
    steps = round(steps) if abs(steps - round(steps)) < 1e-6 else steps
    return round((math.ceil if kind == "max" else math.floor)(steps) * scale, 12)


def derive(hpa, scenario, seeds, jobs, write):
    text = open(scenario).read()
    spec = yaml.safe_load(text)
    keys = expect_keys(hpa)
    with tempfile.TemporaryDirectory() as out:
        runs = run_seeds(hpa, scenario, seeds, out, jobs)
    crashes = sorted(s for s, m in runs.items() if m["crashed"])
    lines, measured = [], []
    for key, old in (spec.get("expect") or {}).items():
        metric, kind, per_axis = keys[key]
        if key == "crash_allowed":
            lines.append(f"  crash_allowed: {str(old).lower()}")
            measured.append(f"crashes {len(crashes)} of {len(seeds)} (allowed)")
            continue
        if key == "crashed":
            if old is False and crashes:
                print(f"{scenario}: seeds {crashes} crash, so `crashed: false` cannot hold",
                      file=sys.stderr)
            lines.append(f"  crashed: {str(old).lower()}")
            measured.append(f"crashes {len(crashes)} of {len(seeds)}")
            continue
        values = [read(m, metric) for s, m in sorted(runs.items()) if not m["crashed"]]
        unmeasured = [s for s, m in sorted(runs.items()) if not m["crashed"] and read(m, metric) is None]
        if unmeasured:
            # e.g. a fault never flagged: no margin covers it, so say so rather than drop it quietly
            print(f"{scenario}: seeds {unmeasured} have no {metric}: `{key}` takes nothing from "
                  "them (and fails there if the run needed it, e.g. a fault never flagged)",
                  file=sys.stderr)
        values = [v for v in values if v is not None]
        if not values:
            sys.exit(f"{scenario}: {key} was not measured on any seed")
        if per_axis:
            bound = [rounded(max(v[i] for v in values) * 1.3, "max") for i in range(3)]
            lines.append(f"  {key}: [{', '.join(fmt(b) for b in bound)}]")
            measured.append(f"{metric} " + ", ".join(
                f"{'xyz'[i]} {fmt(min(v[i] for v in values))}-{fmt(max(v[i] for v in values))}"
                for i in range(3)))
            continue
        lo, hi = min(values), max(values)
        if key == "mpc_failures_max":
            bound = hi
        elif kind == "max":
            bound = rounded(hi + 0.3 * abs(hi), "max")
        else:
            bound = rounded(lo - 0.3 * abs(lo), "min")
        if key.endswith("_min") and metric.endswith("fraction"):
            bound = max(bound, 0.0)
        lines.append(f"  {key}: {fmt(bound)}")
        measured.append(f"{metric} {fmt(lo)}-{fmt(hi)}")
    name = os.path.relpath(scenario)
    comment = [f"# Bounds: `scripts/scenario_bounds.py {name} --seeds {seeds[0]}-{seeds[-1]}`:",
               f"# the worst of seeds {seeds[0]}-{seeds[-1]} with a 30 % margin (docs/results.md, \"How the",
               f"# bounds are set\"); seeds {seeds[-1] + 1}-{seeds[-1] + 10} are held out (ci/check_bounds.sh). Measured:"]
    body = "; ".join(measured)
    while body:
        cut = body[:96].rfind(" ") if len(body) > 96 else len(body)
        comment.append("#   " + body[:cut].strip())
        body = body[cut:].strip()
    block = "\n".join(comment + ["expect:"] + lines) + "\n"
    print(block, end="")
    if write:
        file_lines = text.splitlines(keepends=True)
        start = next(i for i, l in enumerate(file_lines) if l.startswith("expect:"))
        while start > 0 and file_lines[start - 1].startswith("#"):
            start -= 1
        open(scenario, "w").write("".join(file_lines[:start]) + block)


def derivation_seeds(scenario):
    """The seeds a file's bounds were derived from, as its comment states (default 1-30)."""
    m = re.search(r"scenario_bounds\.py \S+ --seeds (\d+)-(\d+)", open(scenario).read())
    return (int(m.group(1)), int(m.group(2))) if m else (1, 30)


# The first seed of the unseen range: no derivation uses seeds this high (derivations take 1-N
# with N at most a few hundred), so a check there is on seeds no bound was ever fitted on.
UNSEEN_FIRST_SEED = 100001


def check(hpa, scenarios, seeds, jobs, held_out=0, min_pass_fraction=1.0):
    """Runs each file on the seeds and lists every seed that fails its bounds; a file fails when
    fewer than min_pass_fraction of its seeds pass. Returns the number of files that fail."""
    failed = 0
    for scenario in scenarios:
        if held_out:
            # the seeds after the file's own derivation range: never one it was fitted on
            last = derivation_seeds(scenario)[1]
            seeds = list(range(last + 1, last + 1 + held_out))
        with tempfile.TemporaryDirectory() as out:
            runs = run_seeds(hpa, scenario, seeds, out, jobs)
        bad = {s: m["expect"]["failed"] for s, m in sorted(runs.items()) if not m["expect"]["passed"]}
        passed = len(seeds) - len(bad)
        print(f"{scenario}: {passed} of {len(seeds)} seeds pass")
        for s, why in bad.items():
            print(f"  seed {s}: {'; '.join(why)}")
        failed += passed < min_pass_fraction * len(seeds) - 1e-9
    return failed


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenarios", nargs="+")
    p.add_argument("--seeds", default=None, help="first-last (derive: 1-30, check: 1-40)")
    p.add_argument("--hpa", default=os.environ.get("HPA", "build/bin/hpa"))
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    p.add_argument("--write", action="store_true", help="rewrite the scenario's bounds")
    p.add_argument("--check", action="store_true", help="check the file's bounds on the seeds")
    p.add_argument("--held-out", type=int, default=0,
                   help="with --check: the N seeds after each file's own derivation range")
    p.add_argument("--unseen", type=int, default=0,
                   help=f"with --check: N seeds from --unseen-from on, which no derivation "
                        "uses; a file fails when fewer than --min-pass of them pass")
    p.add_argument("--unseen-from", type=int, default=UNSEEN_FIRST_SEED,
                   help=f"with --unseen: the first unseen seed (default {UNSEEN_FIRST_SEED}; "
                        f"{UNSEEN_FIRST_SEED + 100} for a second set of 100 after a file was "
                        "re-derived because of failures seen on the first)")
    p.add_argument("--min-pass", type=float, default=None,
                   help="with --check: the share of seeds a file must pass (default 1.0; 0.99 "
                        "with --unseen: the rule's tail allowance)")
    a = p.parse_args()
    if a.check:
        seeds = parse_seeds(a.seeds or "1-40")
        if a.unseen:
            if a.unseen_from < UNSEEN_FIRST_SEED:
                p.error(f"--unseen-from {a.unseen_from}: unseen seeds start at {UNSEEN_FIRST_SEED} "
                        "or later (lower seeds may be derivation seeds)")
            seeds = list(range(a.unseen_from, a.unseen_from + a.unseen))
        min_pass = a.min_pass if a.min_pass is not None else (0.99 if a.unseen else 1.0)
        sys.exit(1 if check(a.hpa, a.scenarios, seeds, a.jobs, a.held_out, min_pass) else 0)
    for scenario in a.scenarios:
        derive(a.hpa, scenario, parse_seeds(a.seeds or "1-30"), a.jobs, a.write)


if __name__ == "__main__":
    main()
