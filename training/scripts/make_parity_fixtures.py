"""Writes the torch-parity fixtures of crates/infer/tests/fixtures/ (committed; small).

    python training/scripts/make_parity_fixtures.py

For a tiny GQ-CNN and a tiny multi-view GQ-CNN (the same layer kinds as the shipped ones, fewer
channels, seeded random weights and normalisation): NAME.json + NAME.safetensors (as
`export_gqcnn` writes them) and NAME.io.safetensors holding inputs (`depth`, `pose`) and torch's
`logits`, computed in float64 and stored as float32.
"""

from __future__ import annotations

from pathlib import Path

import torch
from safetensors.torch import save_file

from mvgrasp_training.export import export_gqcnn
from mvgrasp_training.gqcnn import GQCNN, Architecture, ConvSpec

OUT = Path(__file__).resolve().parents[2] / "crates" / "infer" / "tests" / "fixtures"


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


if __name__ == "__main__":
    main()
