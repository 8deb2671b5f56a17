"""Prints the GQ-CNN benchmark's table from the JSON lines run.sh wrote.

Each file `r{round}.jsonl` holds the lines of one round: `bench_gqcnn` (runtime "rust") and
`bench_torch.py` (runtimes "torch" and "torch-ftz", the latter flushing denormals), one per
model, thread count and batch size. Crops per second are the median over rounds of each run's
median call; Rust's ratio to the faster torch is taken within each round (all runs seconds
apart, under the same load) and then its median is shown.
"""

from __future__ import annotations

import json
import statistics
import sys
from collections import defaultdict
from pathlib import Path

# Fast-VGQ-CNN (the seed paper's successor) reports 128 grasps scored in 12 ms on a CPU.
FAST_VGQ_BATCH = 128
FAST_VGQ_GRASPS_PER_S = 128 / 0.012
# Both runtimes score the same inputs; their mean probabilities must agree this closely.
AGREEMENT = 1e-4


def load(folder: Path) -> dict[tuple, dict[str, dict[int, dict]]]:
    """(model, threads, batch) -> runtime -> round -> line."""
    runs: dict[tuple, dict[str, dict[int, dict]]] = defaultdict(lambda: defaultdict(dict))
    for path in sorted(folder.glob("r*.jsonl")):
        round_ = int(path.stem[1:])
        for text in path.read_text().splitlines():
            if text.strip():
                line = json.loads(text)
                key = (line["model"], line["threads"], line["batch"])
                runs[key][line["runtime"]][round_] = line
    return runs


def labels(models: list[str]) -> dict[str, str]:
    """Each model's file stem, or parent/stem where two models share a stem."""
    stems = [Path(m).stem for m in models]

    def label(model: Path) -> str:
        return model.stem if stems.count(model.stem) == 1 else f"{model.parent.name}/{model.stem}"

    return {m: label(Path(m)) for m in models}


TORCHES = ("torch", "torch-ftz")


def ratio(by_runtime: dict[str, dict[int, dict]]) -> float | None:
    """Median over rounds of Rust's crops/s over the faster torch's in that round."""
    rust = by_runtime.get("rust", {})
    ratios = []
    for r, line in rust.items():
        peers = [by_runtime[t][r]["crops_per_s"] for t in TORCHES if r in by_runtime.get(t, {})]
        if peers:
            ratios.append(line["crops_per_s"] / max(peers))
    return statistics.median(ratios) if ratios else None


def crops_per_s(by_round: dict[int, dict]) -> float | None:
    if not by_round:
        return None
    return statistics.median(line["crops_per_s"] for line in by_round.values())


def fmt(value: float | None, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def main() -> int:
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "out"
    runs = load(folder)
    if not runs:
        print(f"error: no results in {folder}", file=sys.stderr)
        return 2
    models = list(dict.fromkeys(key[0] for key in runs))
    names = labels(models)
    width = max(len(n) for n in names.values())

    print(
        f"| {'model':<{width}} | architecture | threads | batch | Rust crops/s | torch crops/s "
        "| torch FTZ crops/s | Rust/torch |"
    )
    print(f"|{'-' * (width + 2)}|---|---:|---:|---:|---:|---:|---:|")
    missed, worst_disagreement = [], 0.0
    for key in sorted(runs, key=lambda k: (models.index(k[0]), k[1], k[2])):
        model, threads, batch = key
        by_runtime = runs[key]
        first = next(iter(next(iter(by_runtime.values())).values()))
        arch = f"{first['architecture']} (pose {first['pose_inputs']})"
        r = ratio(by_runtime)
        print(
            f"| {names[model]:<{width}} | {arch} | {threads} | {batch} "
            f"| {fmt(crops_per_s(by_runtime.get('rust', {})), '.0f')} "
            f"| {fmt(crops_per_s(by_runtime.get('torch', {})), '.0f')} "
            f"| {fmt(crops_per_s(by_runtime.get('torch-ftz', {})), '.0f')} "
            f"| {fmt(r, '.2f')}x |"
        )
        if r is None or r < 1.0:
            missed.append(f"{names[model]} threads {threads} batch {batch}: {fmt(r, '.2f')}x")
        rust = by_runtime.get("rust", {})
        for t in TORCHES:
            torch = by_runtime.get(t, {})
            for round_ in set(rust) & set(torch):
                diff = abs(rust[round_]["mean_p"] - torch[round_]["mean_p"])
                worst_disagreement = max(worst_disagreement, diff)

    rounds = max(len(by_round) for by in runs.values() for by_round in by.values())
    torch_version = next(
        (line["torch"] for by in runs.values() for line in by.get("torch", {}).values()), "?"
    )
    print(
        f"\nmedian call of each run (>= 5 calls, after a warm-up), median over {rounds} round(s);"
        f" ratios paired within each round, against the faster torch; torch {torch_version},"
        " inference_mode, softmax included in all; FTZ: torch.set_flush_denormal(True) (the"
        " Rust runtime flushes subnormal weights to zero when it loads a network)."
    )
    verdict = "agree" if worst_disagreement <= AGREEMENT else "DISAGREE"
    print(
        f"mean P(robust), Rust vs torch (both settings) on the same inputs: largest difference "
        f"{worst_disagreement:.1e} ({verdict}, tolerance {AGREEMENT:.0e})"
    )

    for model in models:
        parts = []
        for (m, threads, batch), by_runtime in sorted(runs.items()):
            if m != model or batch != FAST_VGQ_BATCH:
                continue
            rust = crops_per_s(by_runtime.get("rust", {}))
            if rust is not None:
                parts.append(
                    f"{threads} thread(s) {rust:,.0f} grasps/s "
                    f"({FAST_VGQ_BATCH / rust * 1e3:.1f} ms, "
                    f"{rust / FAST_VGQ_GRASPS_PER_S:.2f}x)"
                )
        if parts:
            print(
                f"{names[model]} vs Fast-VGQ-CNN (128 grasps in 12 ms on a CPU = "
                f"{FAST_VGQ_GRASPS_PER_S:,.0f} grasps/s): batch {FAST_VGQ_BATCH}, "
                + "; ".join(parts)
            )

    if missed:
        print(
            "target (Rust at least as fast as the faster torch everywhere): NOT met at "
            + "; ".join(missed)
        )
    else:
        print(
            "target (Rust at least as fast as the faster torch at every batch size and thread"
            " count): met"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
