#!/usr/bin/env python3
"""Kill -9 at random moments, resume, compare bytes: the jobs that run for hours must survive it.

For each job: one uninterrupted run (the reference, timed), then ``--kills`` times: a run into a
fresh folder killed with SIGKILL (the whole process group, Ray's workers included) at a moment
drawn uniformly over the reference's duration, then the same command again to resume it to the
end. After each resume every file is compared byte for byte with the reference's, apart from
the files a job names as volatile (wall-clock timings: named in the table). A job passes when
every resume gave identical files, none missing or extra, and no file is left half-written
(``*.tmp``, ``*.partial``).

    python scripts/kill_resume.py                      # every job, 10 kills each
    python scripts/kill_resume.py --jobs grasp-cli evaluate-cli --kills 3

Needs the release binaries (``cargo build --release --bins``) and, for the Python, Ray and
training jobs, the wheel and ``training/`` installed in the running Python (``.ci/run`` makes
such a ``.venv``). Prints a markdown table (the README's reliability table takes it).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# Small configs: each job's reference run takes seconds to a minute on two cores.
GRASP_CONFIG = (
    "stable_poses_per_object = 2\ngrasps_per_pose = 48\nviews_per_pose = 3\n"
    "objects_per_shard = 1\nphysics_fraction = 0.05\n"
)
CATEGORIES = "box,can,mug,bottle,bowl,stapler"
TRAIN_CONFIG = """name = "killed"
seed = 0
[data]
dataset_dir = "{dataset}"
val_fraction = 0.34
[train]
epochs = 6
batch_size = 16
learning_rate = 0.001
threads = 1
"""


@dataclass
class Job:
    """A command that writes into ``{out}``, and the files whose bytes may differ (timings)."""

    name: str
    entry: str
    command: list[str]
    volatile: tuple[str, ...] = ()
    needs: str | None = None  # another job whose reference output it reads
    env: dict[str, str] = field(default_factory=dict)


def jobs(bin_dir: Path, work: Path) -> dict[str, Job]:
    py = sys.executable
    grasp_config = work / "grasp.toml"
    grasp_config.write_text(GRASP_CONFIG)
    dataset = work / "grasp-cli" / "reference"
    train_config = work / "train.toml"
    train_config.write_text(TRAIN_CONFIG.format(dataset=dataset))
    grasp_py = (
        "import sys, mvgrasp.grasp_dataset as g; "
        f"g.generate(sys.argv[1], config={str(grasp_config)!r}, per_category=1, "
        f"categories={CATEGORIES.split(',')!r})"
    )
    rgbd_py = (
        "import sys, mvgrasp; "
        f"mvgrasp.generate_rgbd_dataset(sys.argv[1], per_category=2, "
        f"categories={['box', 'mug', 'can', 'bottle']!r})"
    )
    listed = [
        Job("grasp-cli", "grasp_dataset (Rust CLI)",
            [str(bin_dir / "grasp_dataset"), "--out", "{out}", "--config", str(grasp_config),
             "--categories", CATEGORIES, "--quiet"]),
        Job("grasp-python", "mvgrasp.grasp_dataset.generate (Python)",
            [py, "-c", grasp_py, "{out}"]),
        Job("grasp-ray", "mvgrasp.ray_launcher (Ray, 2 local workers)",
            [py, "-m", "mvgrasp.ray_launcher", "--out", "{out}", "--config", str(grasp_config),
             "--per-category", "1", "--categories", CATEGORIES, "--num-cpus", "2"]),
        Job("rgbd-cli", "render (Rust CLI, RGB-D dataset)",
            [str(bin_dir / "render"), "--out", "{out}", "--categories", "box,mug,can,bottle",
             "--per-category", "2", "--quiet"]),
        Job("rgbd-python", "mvgrasp.generate_rgbd_dataset (Python)",
            [py, "-c", rgbd_py, "{out}"]),
        Job("training", "python -m mvgrasp_training.train (GQ-CNN, 6 epochs)",
            [py, "-m", "mvgrasp_training.train", str(train_config), "--out", "{out}"],
            needs="grasp-cli"),
        Job("evaluate-cli", "evaluate (Rust CLI, grasps on rendered depth)",
            [str(bin_dir / "evaluate"), "--out", "{out}", "--set", "held-out",
             "--policy", "depth", "--suite", "grasps", "--plain"]),
    ]
    return {job.name: job for job in listed}


def start(job: Job, out: Path, log) -> subprocess.Popen:
    command = [part.replace("{out}", str(out)) for part in job.command]
    env = dict(os.environ, **job.env)
    return subprocess.Popen(command, stdout=log, stderr=log, env=env, cwd=ROOT,
                            start_new_session=True)


def kill_group(process: subprocess.Popen) -> None:
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    process.wait()


def files(folder: Path) -> dict[str, str]:
    """Relative path -> sha256 of every file under ``folder``."""
    found = {}
    for path in sorted(folder.rglob("*")):
        if path.is_file():
            found[str(path.relative_to(folder))] = hashlib.sha256(path.read_bytes()).hexdigest()
    return found


def run_job(job: Job, work: Path, kills: int, rng: random.Random, log) -> dict:
    folder = work / job.name
    reference, killed = folder / "reference", folder / "killed"
    if not (reference / ".complete").exists():
        shutil.rmtree(reference, ignore_errors=True)
        started = time.monotonic()
        status = start(job, reference, log).wait()
        if status != 0:
            raise RuntimeError(f"{job.name}: the reference run failed (exit {status}); see the log")
        (reference / ".complete").write_text(f"{time.monotonic() - started:.3f}\n")
    duration = float((reference / ".complete").read_text())
    expected = {k: v for k, v in files(reference).items() if k != ".complete"}
    volatile = [k for k in expected if Path(k).name in job.volatile]
    landed, statuses, differ, extra, leftovers = 0, [], set(), set(), set()
    for trial in range(kills):
        # A fresh folder each time: the kill lands at a uniform moment of a whole run.
        shutil.rmtree(killed, ignore_errors=True)
        process = start(job, killed, log)
        moment = rng.uniform(0.02, 0.98) * duration
        try:
            process.wait(timeout=moment)
        except subprocess.TimeoutExpired:
            kill_group(process)
            landed += 1
        status = start(job, killed, log).wait()
        statuses.append(status)
        got = files(killed)
        half = [k for k in got if k.endswith((".tmp", ".partial"))]
        leftovers.update(half)
        differ.update(f"{k} (kill {trial + 1})" for k in expected
                      if k not in volatile and got.get(k) != expected[k])  # fmt: skip
        extra.update(k for k in got if k not in expected and k not in half)
    status = max(statuses, default=0)
    differ, extra, leftovers = sorted(differ), sorted(extra), sorted(leftovers)
    return {
        "job": job.name,
        "entry": job.entry,
        "seconds": duration,
        "kills": kills,
        "landed": landed,
        "status": status,
        "compared": len(expected) - len(volatile),
        "volatile": volatile,
        "differ": differ,
        "extra": extra,
        "leftovers": leftovers,
        "identical": status == 0 and not differ and not extra and not leftovers,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", nargs="*", help="job names (default: all)")
    parser.add_argument("--kills", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--bin-dir", type=Path, default=ROOT / "target" / "release")
    parser.add_argument("--work", type=Path, help="kept working folder (default: a temporary one)")
    args = parser.parse_args(argv)
    work = args.work or Path(tempfile.mkdtemp(prefix="mvgrasp-kill-"))
    work.mkdir(parents=True, exist_ok=True)
    every = jobs(args.bin_dir, work)
    names = args.jobs or list(every)
    unknown = [n for n in names if n not in every]
    if unknown:
        parser.error(f"unknown jobs {unknown}; the jobs: {', '.join(every)}")
    # A job that reads another's output runs after it.
    ordered = [n for n in every if n in names or any(every[m].needs == n for m in names)]
    rng = random.Random(args.seed)
    rows, failed = [], 0
    print("| job | entry point | reference run (s) | kills (landed mid-run) | files compared | "
          "identical | not compared (timings) |")
    print("|---|---|---|---|---|---|---|")
    with open(work / "jobs.log", "ab") as log:
        for name in ordered:
            job = every[name]
            row = run_job(job, work, args.kills if name in names else 0, rng, log)
            if name not in names:
                continue
            rows.append(row)
            failed += not row["identical"]
            verdict = "yes" if row["identical"] else (
                f"NO (exit {row['status']}; differ {row['differ'][:5]}; extra {row['extra'][:5]};"
                f" half-written {row['leftovers'][:5]})")
            print(f"| {name} | {job.entry} | {row['seconds']:.1f} | {row['kills']} ({row['landed']})"
                  f" | {row['compared']} | {verdict} | {', '.join(row['volatile']) or '-'} |",
                  flush=True)
    print(f"\nwork folder: {work} (log: {work / 'jobs.log'})")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
