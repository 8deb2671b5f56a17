"""The torch GQ-CNNs: shapes, the description Rust rebuilds them from, and Dex-Net's LRN."""

from __future__ import annotations

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from mvgrasp_training.gqcnn import ARCHITECTURES, GQCNN, dexnet2  # noqa: E402


@pytest.mark.parametrize("name", sorted(ARCHITECTURES))
@pytest.mark.parametrize("pose_inputs", [1, 2])
def test_logits_have_the_batch_shape(name: str, pose_inputs: int) -> None:
    net = GQCNN(ARCHITECTURES[name](pose_inputs=pose_inputs))
    logits = net(torch.rand(5, 1, 32, 32), torch.rand(5, pose_inputs))
    assert logits.shape == (5, 2)
    assert torch.isfinite(logits).all()


def test_the_description_is_json_and_names_every_layer() -> None:
    arch = dexnet2(pose_inputs=2)
    text = json.dumps(arch.describe())
    back = json.loads(text)
    assert [c["kernel"] for c in back["convs"]] == [7, 5, 3, 3]
    assert back["image_fc"] == 1024 and back["pose_fc"] == 16 and back["merge_fc"] == 1024
    assert back["pose_inputs"] == 2


def test_dexnet2_parameter_count_matches_its_layers() -> None:
    net = GQCNN(dexnet2())
    convs = (7 * 7 * 1 + 1) * 64 + (5 * 5 * 64 + 1) * 64 + 2 * (3 * 3 * 64 + 1) * 64
    fcs = (64 * 8 * 8 + 1) * 1024 + (1 + 1) * 16 + (1024 + 16 + 1) * 1024 + (1024 + 1) * 2
    assert sum(p.numel() for p in net.parameters()) == convs + fcs


def test_the_lrn_is_tensorflows_with_depth_radius_2() -> None:
    # TensorFlow: b_c = a_c / (bias + alpha * sum_{|d - c| <= r} a_d^2) ** beta.
    arch = dexnet2()
    a = np.random.default_rng(0).normal(size=(2, 9, 4, 4)).astype(np.float64)
    r, alpha, beta, bias = 2, 2e-5, 0.75, 1.0
    expected = np.empty_like(a)
    for c in range(a.shape[1]):
        window = a[:, max(0, c - r) : c + r + 1]
        expected[:, c] = a[:, c] / (bias + alpha * (window**2).sum(axis=1)) ** beta
    lrn = torch.nn.LocalResponseNorm(arch.lrn_size, arch.lrn_alpha, arch.lrn_beta, arch.lrn_k)
    got = lrn(torch.from_numpy(a)).numpy()
    assert np.allclose(got, expected, rtol=1e-10, atol=1e-12)


def test_export_writes_every_tensor_and_the_description(tmp_path) -> None:
    from safetensors.torch import load_file

    from mvgrasp_training.export import export_gqcnn

    net = GQCNN(ARCHITECTURES["small"](pose_inputs=2))
    net.set_normalisation(0.6, 0.03, torch.tensor([0.7, 1.0]), torch.tensor([0.05, 0.3]))
    path = export_gqcnn(net, tmp_path / "net", {"data": "test"})
    description = json.loads(path.read_text())
    assert description["format"] == "mvgrasp-gqcnn/1"
    assert description["normalisation"]["pose_mean"] == pytest.approx([0.7, 1.0])
    tensors = load_file(str(tmp_path / description["weights"]))
    assert set(tensors) == set(net.state_dict()) == set(description["tensors"])
    for name, value in net.state_dict().items():
        assert torch.equal(tensors[name], value)


def test_an_export_reads_back_into_the_same_network(tmp_path) -> None:
    from safetensors.torch import load_file, save_file

    from mvgrasp_training.export import export_gqcnn, load_gqcnn

    torch.manual_seed(1)
    net = GQCNN(ARCHITECTURES["small"](pose_inputs=2)).eval()
    net.set_normalisation(0.7, 0.05, torch.tensor([0.7, 1.0]), torch.tensor([0.05, 0.3]))
    path = export_gqcnn(net, tmp_path / "net")
    back, description = load_gqcnn(path)
    assert description["architecture"]["pose_inputs"] == 2
    depth, pose = torch.rand(5, 1, 32, 32) + 0.5, torch.rand(5, 2)
    with torch.no_grad():
        assert torch.equal(net(depth, pose), back(depth, pose))
    tensors = load_file(str(tmp_path / "net.safetensors"))
    tensors["image_fc.weight"] = tensors["image_fc.weight"][:, :-1].contiguous()
    save_file(tensors, str(tmp_path / "net.safetensors"))
    with pytest.raises(ValueError, match=r"net\.safetensors: tensor image_fc\.weight has shape"):
        load_gqcnn(path)
    (tmp_path / "bad.json").write_text('{"format": "something-else"}')
    with pytest.raises(ValueError, match=r"bad\.json: format 'something-else'"):
        load_gqcnn(tmp_path / "bad.json")


def test_evaluate_scores_an_export_on_a_dataset(tmp_path, monkeypatch) -> None:
    import mvgrasp_training.evaluate as evaluate
    from mvgrasp_training.export import export_gqcnn
    from mvgrasp_training.train import Arrays

    torch.manual_seed(2)
    net = GQCNN(ARCHITECTURES["small"](pose_inputs=1)).eval()
    path = export_gqcnn(net, tmp_path / "net")
    rng = np.random.default_rng(0)
    data = Arrays(
        depth=rng.uniform(0.6, 0.7, (50, 1, 32, 32)).astype(np.float32),
        pose=rng.uniform(0.6, 0.7, (50, 1)).astype(np.float32),
        label=rng.integers(0, 2, 50),
        object_id=np.zeros(50, dtype=np.int64),
    )
    monkeypatch.setattr(evaluate, "load_arrays", lambda root, pose_inputs, label: data)
    result = evaluate.evaluate(path, [tmp_path / "data"])[str(tmp_path / "data")]
    with torch.no_grad():
        prob = torch.softmax(net(torch.from_numpy(data.depth), torch.from_numpy(data.pose)), 1)[:, 1]
    predicted = (prob.numpy() > 0.5) == (data.label == 1)
    assert result["count"] == 50
    assert abs(result["accuracy"] - predicted.mean()) < 1e-9
    assert 0.0 <= result["recall_at_0.9"] <= result["recall_at_0.8"] <= result["recall"] <= 1.0
    # Held out: only the objects a 0.5 split with seed 0 holds out (one of the two here).
    data.object_id[25:] = 1
    held = evaluate.evaluate(path, [tmp_path / "data"], held_out=(0.5, 0))[str(tmp_path / "data")]
    assert held["count"] == 25


def test_top_k_precision_averages_each_objects_best() -> None:
    from mvgrasp_training.evaluate import top_k_precision

    prob = np.array([0.9, 0.8, 0.1, 0.7, 0.95, 0.2, 0.3])
    label = np.array([1, 0, 1, 0, 0, 1, 1])
    objects = np.array([0, 0, 0, 1, 1, 1, 1])
    # Object 0's best (0.9) is positive, object 1's (0.95) is not.
    assert top_k_precision(prob, label, objects, 1) == 0.5
    # Top 2: object 0 has 1 of 2, object 1 has 0 of 2 (0.95, 0.7).
    assert top_k_precision(prob, label, objects, 2) == 0.25
    # More than an object has: all of its datapoints.
    assert top_k_precision(prob, label, objects, 10) == (2 / 3 + 2 / 4) / 2
