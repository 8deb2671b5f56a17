#!/usr/bin/env python3
"""Paired comparison of `evaluate` policies: the same plans (set, object, pose, seed) under
each policy, leaving out those whose object toppled under any of them (the trial tests the
pose there, not the grasp), a missing grasp counted as a failure.

    python scripts/paired_outcomes.py RUN/records.jsonl [OTHER_RUN/records.jsonl ...]

Prints, per object set and over all, each policy's held share of the common plans and its
precision (held of grasps returned), then for each pair of policies the plans only one held
and McNemar's z. Policies of the same name in two files are told apart by the run's folder.
Reads the records `evaluate` writes; needs nothing beyond Python.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
from collections import defaultdict
from pathlib import Path

Plan = tuple[str, str, str, str]


def read(paths: list[Path]) -> dict[Plan, dict[str, str]]:
    """Per plan, each policy's outcome."""
    names = {p: p.parent.name for p in paths}
    plans: dict[Plan, dict[str, str]] = defaultdict(dict)
    for path in paths:
        try:
            lines = path.read_text().splitlines()
        except OSError as e:
            sys.exit(f"error: {path}: {e.strerror}")
        for n, line in enumerate(lines, 1):
            try:
                record = json.loads(line)
                key = record["key"]
                if not key.startswith("grasp|"):
                    continue
                _, group, obj, pose, policy, seed = key.split("|")
                outcome = record["value"]["outcome"]
            except (json.JSONDecodeError, KeyError, TypeError, ValueError) as e:
                sys.exit(f"error: {path}:{n}: not an evaluate record ({e})")
            name = policy if len(paths) == 1 else f"{names[path]}:{policy}"
            plans[(group, obj, pose, seed)][name] = outcome
    return plans


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("records", nargs="+", type=Path)
    args = parser.parse_args()
    plans = read(args.records)
    policies = sorted({p for outcomes in plans.values() for p in outcomes})
    common = {
        plan: outcomes
        for plan, outcomes in plans.items()
        if all(p in outcomes for p in policies)
        and not any(outcomes[p] == "toppled" for p in policies)
    }
    if not common:
        sys.exit("error: no plan was made by every policy without its object toppling")
    print(f"{len(common)} common plans of {len(plans)}; policies: {', '.join(policies)}\n")
    groups = sorted({plan[0] for plan in common}) + ["all"]
    print("| policy | " + " | ".join(groups) + " | precision (all) |")
    print("|---" * (len(groups) + 2) + "|")
    for policy in policies:
        cells = []
        for group in groups:
            outcomes = [o[policy] for plan, o in common.items() if group in ("all", plan[0])]
            held = sum(o == "held" for o in outcomes)
            cells.append(f"{100 * held / len(outcomes):.1f}% ({held} of {len(outcomes)})")
        returned = [o[policy] for o in common.values() if o[policy] != "no grasp"]
        held = sum(o == "held" for o in returned)
        precision = f"{100 * held / len(returned):.0f}%" if returned else "-"
        print(f"| {policy} | " + " | ".join(cells) + f" | {precision} |")
    print()
    for a, b in itertools.combinations(policies, 2):
        only_a = sum(o[a] == "held" and o[b] != "held" for o in common.values())
        only_b = sum(o[b] == "held" and o[a] != "held" for o in common.values())
        z = (only_b - only_a) / math.sqrt(only_a + only_b) if only_a + only_b else 0.0
        print(f"{a} held alone {only_a}, {b} alone {only_b}: McNemar z = {z:+.2f}")


if __name__ == "__main__":
    main()
