"""Writes the torch-parity fixtures (committed; small).

    python training/scripts/make_parity_fixtures.py

1. crates/infer/tests/fixtures/: for a tiny GQ-CNN and a tiny multi-view GQ-CNN (the same layer
   kinds as the shipped ones, fewer channels, seeded random weights and normalisation):
   NAME.json + NAME.safetensors (as `export_gqcnn` writes them) and NAME.io.safetensors holding
   inputs (`depth`, `pose`) and torch's `logits`, computed in float64 and stored as float32.
2. tests/fixtures/shipped/NAME.io.safetensors for every shipped network (models/NAME.json):
   16 seeded synthetic crops (a table with a raised block, 1 mm noise) and poses, and torch's
   logits of the shipped weights, for the Rust test of the networks `plan` runs.
"""

from __future__ import annotations

from pathlib import Path

import torch
from safetensors.torch import save_file

from mvgrasp_training.export import export_gqcnn, load_gqcnn
from mvgrasp_training.gqcnn import GQCNN, Architecture, ConvSpec

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "crates" / "infer" / "tests" / "fixtures"
SHIPPED_OUT = ROOT / "tests" / "fixtures" / "shipped"


def tiny(pose_inputs: int) -> Architecture:
    return Architecture(
        name=f"tiny_pose{pose_inputs}",
        image_size_px=16,
        convs=(ConvSpec(6, 5), ConvSpec(8, 3, lrn=True, pool=2), ConvSpec(8, 3, lrn=True, pool=2)),
        image_fc=24,
        pose_inputs=pose_inputs,
        pose_fc=8,
        merge_fc=16,
    )


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    for pose_inputs in (1, 2):
        torch.manual_seed(pose_inputs)
        net = GQCNN(tiny(pose_inputs))
        net.set_normalisation(0.6, 0.02, torch.rand(pose_inputs) + 0.5, torch.rand(pose_inputs) + 0.1)
        name = f"gqcnn_tiny_pose{pose_inputs}"
        export_gqcnn(net, OUT / name, {"purpose": "parity fixture, random weights"})
        depth = 0.6 + 0.05 * torch.randn(7, 1, 16, 16)
        pose = torch.rand(7, pose_inputs) + 0.5
        with torch.no_grad():
            logits = net.double()(depth.double(), pose.double()).float()
        save_file({"depth": depth, "pose": pose, "logits": logits}, str(OUT / f"{name}.io.safetensors"))
        print(f"wrote {name}: logits {logits[0].tolist()}")
    SHIPPED_OUT.mkdir(parents=True, exist_ok=True)
    for model in sorted((ROOT / "models").glob("*.json")):
        net, _ = load_gqcnn(model)
        gen = torch.Generator().manual_seed(0)
        n, side = 16, net.arch.image_size_px
        depth = torch.full((n, 1, side, side), 0.7)
        for i in range(n):
            r0, c0 = torch.randint(0, side // 2, (2,), generator=gen).tolist()
            h, w = torch.randint(side // 4, side // 2, (2,), generator=gen).tolist()
            depth[i, 0, r0 : r0 + h, c0 : c0 + w] -= 0.03 + 0.03 * torch.rand(1, generator=gen)
        depth += 0.001 * torch.randn(depth.shape, generator=gen)
        pose = torch.cat(
            [0.6 + 0.15 * torch.rand(n, 1, generator=gen), 0.2 + 1.37 * torch.rand(n, 1, generator=gen)],
            dim=1,
        )[:, : net.arch.pose_inputs].contiguous()
        with torch.no_grad():
            logits = net.double()(depth.double(), pose.double()).float()
        save_file(
            {"depth": depth, "pose": pose, "logits": logits},
            str(SHIPPED_OUT / f"{model.stem}.io.safetensors"),
        )
        print(f"wrote shipped/{model.stem}: logits {logits[0].tolist()}")


if __name__ == "__main__":
    main()
