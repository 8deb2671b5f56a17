"""Writes the torch-parity fixtures (committed; small).

    python training/scripts/make_parity_fixtures.py

1. crates/infer/tests/fixtures/: for a tiny GQ-CNN and a tiny multi-view GQ-CNN (the same layer
   kinds as the shipped ones, fewer channels, seeded random weights and normalisation):
   NAME.json + NAME.safetensors (as `export_gqcnn` writes them) and NAME.io.safetensors holding
   inputs (`depth`, `pose`) and torch's `logits`, computed in float64 and stored as float32.
2. tests/fixtures/shipped/NAME.io.safetensors for every shipped network (models/NAME.json):
   16 seeded synthetic crops (a table with a raised block, 1 mm noise) and poses, and torch's
   logits of the shipped weights, for the Rust test of the networks `plan` runs.
3. crates/infer/tests/fixtures/: for a tiny Learnt Stereo Machine (the shipped one's layers,
   fewer channels, seeded random weights and norm affines) lsm_tiny.json + .safetensors (as
   `export_lsm` writes them) and lsm_tiny.io.safetensors: 3 RGB views of random colours, their
   cameras on a hemisphere, torch's depth; and lsm_ops.io.safetensors: inputs and torch outputs
   of each op the LSM adds to the runtime (3-D convolution, transposed convolution, instance
   norm, the convolutional GRU cell, unprojection, ray projection, bilinear and area resizing).
   All computed in float64, stored as float32.
4. crates/infer/tests/fixtures/: for a tiny multi-view stereo network (the shipped one's layers,
   fewer channels and planes, seeded random weights) mvs_tiny.json + .safetensors (as
   `export_mvs` writes them) and mvs_tiny.io.safetensors: 3 RGB views of random colours, their
   cameras on a hemisphere, torch's depth, confidence and both stages' depths, and the inputs and
   outputs of its geometry (the workspace's depth range, the hypotheses, one correlation
   volume). Computed in float64, stored as float32.

5. crates/infer/tests/fixtures/: for a tiny sweep refiner (3 dilated layers of 4 channels,
   seeded random weights) sweep_refiner_tiny.json + .safetensors and
   sweep_refiner_tiny.io.safetensors: random features and torch's correction and confidence,
   computed in float64, stored as float32.

``--only mvs`` / ``--only sweep_refiner`` writes the fourth / fifth part alone (the others stay
as they are).
"""

from __future__ import annotations

import math
from pathlib import Path

import torch
from safetensors.torch import save_file
from torch.nn import functional as F

from mvgrasp_training.export import export_gqcnn, export_lsm, export_mvs, load_gqcnn
from mvgrasp_training.gqcnn import GQCNN, Architecture, ConvSpec
from mvgrasp_training.lsm import (
    LSM,
    ConvGru3d,
    LsmArchitecture,
    grid_centre,
    project,
    unproject,
    voxel_centres,
)

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


def look_at(eye: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """camera_from_world (4x4, float64) of an OpenCV camera at ``eye`` looking at ``target``."""
    z = target - eye
    z = z / z.norm()
    up = torch.tensor([0.0, 0.0, 1.0], dtype=torch.float64)
    if abs(float(z @ up)) > 0.99:
        up = torch.tensor([0.0, 1.0, 0.0], dtype=torch.float64)
    x = torch.linalg.cross(z, up)
    x = x / x.norm()
    y = torch.linalg.cross(z, x)
    rotation = torch.stack([x, y, z])  # rows: the camera's axes in the world
    out = torch.eye(4, dtype=torch.float64)
    out[:3, :3] = rotation
    out[:3, 3] = -rotation @ eye
    return out


def hemisphere_cameras(views: int, width: int, height: int, gen: torch.Generator) -> tuple:
    """``views`` cameras 0.45-0.6 m from a point near the origin (the first from above), with
    their K at ``width`` x ``height``: (k (V, 3, 3), camera_from_world (V, 4, 4)), float64."""
    target = torch.tensor([0.01, -0.02, 0.05], dtype=torch.float64)
    poses = []
    for v in range(views):
        distance = 0.45 + 0.15 * torch.rand(1, generator=gen, dtype=torch.float64).item()
        polar = (
            0.05 if v == 0 else 0.3 + 0.8 * torch.rand(1, generator=gen, dtype=torch.float64).item()
        )
        azimuth = 6.28 * torch.rand(1, generator=gen, dtype=torch.float64).item()
        eye = target + distance * torch.tensor(
            [
                math.sin(polar) * math.cos(azimuth),
                math.sin(polar) * math.sin(azimuth),
                math.cos(polar),
            ],
            dtype=torch.float64,
        )
        poses.append(look_at(eye, target))
    k = torch.tensor(
        [
            [0.9 * width, 0.0, (width - 1) / 2],
            [0.0, 0.9 * width, (height - 1) / 2],
            [0.0, 0.0, 1.0],
        ],
        dtype=torch.float64,
    )
    return k.expand(views, 3, 3).contiguous(), torch.stack(poses)


def randomise_norms(net: torch.nn.Module, gen: torch.Generator) -> None:
    """Instance norms' affine weights away from their (1, 0) initialisation, so that the test
    sees them used."""
    for module in net.modules():
        if isinstance(module, (torch.nn.InstanceNorm2d, torch.nn.InstanceNorm3d)):
            module.weight.data = 0.5 + torch.rand(module.weight.shape, generator=gen)
            module.bias.data = 0.2 * torch.randn(module.bias.shape, generator=gen)


def lsm_fixtures() -> None:
    gen = torch.Generator().manual_seed(7)
    torch.manual_seed(7)
    arch = LsmArchitecture(
        image_width=32,
        image_height=24,
        features=8,
        grid_size=8,
        grid_side_m=0.3,
        gru_channels=6,
        ray_samples=6,
    )
    net = LSM(arch)
    randomise_norms(net, gen)
    export_lsm(net, OUT / "lsm_tiny", {"purpose": "parity fixture, random weights"})
    views = 3
    k, pose = hemisphere_cameras(views, arch.image_width, arch.image_height, gen)
    images = torch.rand(
        1, views, 3, arch.image_height, arch.image_width, generator=gen, dtype=torch.float64
    )
    with torch.no_grad():
        depth = net.double()(images, k[None], pose[None])[0]
    save_file(
        {
            "images": images[0].float(),
            "k": k.float(),
            "camera_from_world": pose.float(),
            "depth": depth.float(),
        },
        str(OUT / "lsm_tiny.io.safetensors"),
    )
    print(f"wrote lsm_tiny: depth {depth.min().item():.4f}..{depth.max().item():.4f} m")

    d = torch.float64
    ops: dict[str, torch.Tensor] = {}
    with torch.no_grad():
        x = torch.randn(1, 3, 6, 5, 7, generator=gen, dtype=d)
        w = torch.randn(4, 3, 3, 3, 3, generator=gen, dtype=d)
        b = torch.randn(4, generator=gen, dtype=d)
        ops |= {
            "conv3d.x": x,
            "conv3d.w": w,
            "conv3d.b": b,
            "conv3d.y": F.conv3d(x, w, b, stride=2, padding=1),
        }
        x = torch.randn(1, 4, 3, 4, 2, generator=gen, dtype=d)
        w = torch.randn(4, 3, 4, 4, 4, generator=gen, dtype=d)
        b = torch.randn(3, generator=gen, dtype=d)
        y = F.conv_transpose3d(x, w, b, stride=2, padding=1)
        ops |= {
            "conv_transpose3d.x": x,
            "conv_transpose3d.w": w,
            "conv_transpose3d.b": b,
            "conv_transpose3d.y": y,
        }
        x = 3 + 2 * torch.randn(2, 3, 4, 5, 6, generator=gen, dtype=d)
        nw, nb = torch.rand(3, generator=gen, dtype=d) + 0.5, torch.randn(3, generator=gen, dtype=d)
        y = F.instance_norm(x, weight=nw, bias=nb, eps=1e-5)
        ops |= {
            "instance_norm3d.x": x,
            "instance_norm3d.w": nw,
            "instance_norm3d.b": nb,
            "instance_norm3d.y": y,
        }
        cell = ConvGru3d(3, 4).double()
        x = torch.randn(1, 3, 5, 4, 6, generator=gen, dtype=d)
        h = torch.tanh(torch.randn(1, 4, 5, 4, 6, generator=gen, dtype=d))
        ops |= {
            "gru.x": x,
            "gru.h": h,
            "gru.gates.weight": cell.gates.weight,
            "gru.gates.bias": cell.gates.bias,
            "gru.candidate.weight": cell.candidate.weight,
            "gru.candidate.bias": cell.candidate.bias,
            "gru.y": cell(x, h),
        }
        features = torch.randn(1, 5, 12, 16, generator=gen, dtype=d)
        k, pose = hemisphere_cameras(2, 16, 12, gen)
        centre = grid_centre(pose[None])
        voxels = voxel_centres(centre, 8, 0.3)
        y = unproject(features, k[:1], pose[:1], voxels, 0.15)
        ops |= {
            "unproject.features": features,
            "unproject.k": k[0],
            "unproject.camera_from_world": pose[0],
        }
        ops |= {"unproject.centre": centre[0], "unproject.y": y}
        grid = torch.randn(1, 3, 8, 8, 8, generator=gen, dtype=d)
        y = project(grid, k[1:2], pose[1:2], centre, 0.3, 5, 12, 16)
        ops |= {
            "project.grid": grid,
            "project.k": k[1],
            "project.camera_from_world": pose[1],
            "project.y": y,
        }
        x = torch.randn(2, 3, 5, 7, generator=gen, dtype=d)
        ops |= {"resize.x": x, "resize.bilinear": F.interpolate(x, size=(10, 14), mode="bilinear")}
        x = torch.rand(1, 3, 30, 40, generator=gen, dtype=d)
        ops |= {"resize.area_x": x, "resize.area": F.interpolate(x, size=(12, 16), mode="area")}
    save_file(
        {k: v.float().contiguous() for k, v in ops.items()}, str(OUT / "lsm_ops.io.safetensors")
    )
    print(f"wrote lsm_ops: {len(ops)} tensors")


def mvs_fixtures() -> None:
    from mvgrasp_training.mvs import (
        MVS,
        MvsArchitecture,
        correlation_volume,
        depth_range,
        inverse_depth_planes,
    )

    gen = torch.Generator().manual_seed(11)
    torch.manual_seed(11)
    arch = MvsArchitecture(
        image_width=32,
        image_height=24,
        features=4,
        groups=2,
        coarse_planes=8,
        fine_planes=4,
        fine_step_m=0.004,
        regulariser=4,
    )
    net = MVS(arch)
    export_mvs(net, OUT / "mvs_tiny", {"purpose": "parity fixture, random weights"})
    views = 3
    k, pose = hemisphere_cameras(views, arch.image_width, arch.image_height, gen)
    images = torch.rand(
        1, views, 3, arch.image_height, arch.image_width, generator=gen, dtype=torch.float64
    )
    io: dict[str, torch.Tensor] = {}
    with torch.no_grad():
        out = net.double()(images, k[None], pose[None])
        io |= {
            "images": images[0],
            "k": k,
            "camera_from_world": pose,
            "depth": out.depth[0],
            "confidence": out.confidence[0],
            "coarse": out.coarse[0],
            "fine": out.fine[0],
        }
        centre = grid_centre(pose[None])
        near, far = depth_range(k[1:2], pose[1:2], centre, arch, 24, 32)
        planes = inverse_depth_planes(near, far, 6)
        features = torch.randn(1, views, 4, 24, 32, generator=gen, dtype=torch.float64)
        volume = correlation_volume(features, k[None], pose[None], 1, planes, 2)
        io |= {
            "range.centre": centre[0],
            "range.near": near[0],
            "range.far": far[0],
            "planes": planes[0],
            "volume.features": features[0],
            "volume.y": volume[0],
        }
    save_file(
        {key: value.float().contiguous() for key, value in io.items()},
        str(OUT / "mvs_tiny.io.safetensors"),
    )
    print(f"wrote mvs_tiny: depth {out.depth.min().item():.4f}..{out.depth.max().item():.4f} m")


def sweep_refiner_fixtures() -> None:
    from mvgrasp_training.export import export_sweep_refiner
    from mvgrasp_training.sweep_refiner import SweepRefiner, SweepRefinerArchitecture

    torch.manual_seed(13)
    gen = torch.Generator().manual_seed(13)
    arch = SweepRefinerArchitecture(channels=4, dilations=(1, 2, 4), step_m=0.01)
    net = SweepRefiner(arch)
    export_sweep_refiner(net, OUT / "sweep_refiner_tiny", {"purpose": "parity fixture, random weights"})
    features = torch.randn(1, arch.inputs, 13, 17, generator=gen, dtype=torch.float64)
    with torch.no_grad():
        correction, logit = net.double()(features)
    save_file(
        {
            "features": features.float().contiguous(),
            "correction_m": correction[0].float().contiguous(),
            "confidence": torch.sigmoid(logit[0]).float().contiguous(),
        },
        str(OUT / "sweep_refiner_tiny.io.safetensors"),
    )
    print(f"wrote sweep_refiner_tiny: correction {correction.abs().max().item():.4f} m at most")


def main() -> None:
    import sys

    if sys.argv[1:] == ["--only", "mvs"]:
        mvs_fixtures()
        return
    if sys.argv[1:] == ["--only", "sweep_refiner"]:
        sweep_refiner_fixtures()
        return
    sweep_refiner_fixtures()
    mvs_fixtures()
    lsm_fixtures()
    OUT.mkdir(parents=True, exist_ok=True)
    for pose_inputs in (1, 2):
        torch.manual_seed(pose_inputs)
        net = GQCNN(tiny(pose_inputs))
        net.set_normalisation(
            0.6, 0.02, torch.rand(pose_inputs) + 0.5, torch.rand(pose_inputs) + 0.1
        )
        name = f"gqcnn_tiny_pose{pose_inputs}"
        export_gqcnn(net, OUT / name, {"purpose": "parity fixture, random weights"})
        depth = 0.6 + 0.05 * torch.randn(7, 1, 16, 16)
        pose = torch.rand(7, pose_inputs) + 0.5
        with torch.no_grad():
            logits = net.double()(depth.double(), pose.double()).float()
        save_file(
            {"depth": depth, "pose": pose, "logits": logits}, str(OUT / f"{name}.io.safetensors")
        )
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
            [
                0.6 + 0.15 * torch.rand(n, 1, generator=gen),
                0.2 + 1.37 * torch.rand(n, 1, generator=gen),
            ],
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
