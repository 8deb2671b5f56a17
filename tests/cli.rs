//! The command-line tools as a user runs them.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use std::process::Command;

use crate::shared_data::shared_data;

fn plan(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_plan"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn plan_with_no_arguments_plans_on_depth_from_rgb_beside_the_rendered_depth() {
    let out = plan(&[]);
    // A grasp (0) or none found (3, a result): never an error.
    assert!(
        matches!(out.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.starts_with("mug_000 (built-in, seed 0)"), "{text}");
    assert!(
        text.contains("watertight") && !text.contains("NOT watertight"),
        "{text}"
    );
    assert!(text.contains("training views: 20 views"), "{text}");
    assert!(text.contains("test views:     10 views"), "{text}");
    assert!(text.contains("stable"), "{text}");
    // RGB -> depth by the plane-sweep baseline from 5 views 0.65 m away -> the multi-view
    // planner over all of them, its grasp ranked by its chance to hold.
    assert!(
        text.contains("plan: gqcnn_small_multiview (the multi-view planner: the views fused")
            && text.contains("5 view(s) 0.65 m away"),
        "{text}"
    );
    assert!(
        !text.contains("      1   22.9 deg           0             -"),
        "every view plans: {text}"
    );
    assert!(
        text.contains("predicted by the plane-sweep baseline"),
        "{text}"
    );
    assert!(
        text.contains("best grasp: view ") || text.contains("no grasp: "),
        "{text}"
    );
    // The same run on the rendered depth, beside it, with its checks.
    let line = text
        .lines()
        .find(|l| l.starts_with("on the rendered (true) depth, the same run: "))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        line.contains("quality") && line.contains("physics") || line.contains("no grasp"),
        "{line}"
    );
    assert!(line.contains("(on the predicted depth: "), "{line}");
}

#[test]
fn plan_on_rendered_depth_describes_the_mug_and_checks_the_grasp() {
    let out = plan(&["--depth-from", "rendered", "--fuse"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("best grasp: view "), "{text}");
    assert!(text.contains("g* = (p = ("), "{text}");
    assert!(text.contains("analytic check: robust epsilon"), "{text}");
    assert!(
        text.contains("physics (rapier: close, lift, shake): "),
        "{text}"
    );
    assert!(!text.contains("predicted by"), "{text}");
    // The top-down GQ-CNN alone, as Dex-Net 2.0.
    let text = plan_text(&["--depth-from", "rendered", "--no-physics", "--no-fuse"]);
    assert!(
        text.contains("plan: gqcnn_small_topdown (GQ-CNN)")
            && text.contains("1 view(s) 0.70 m away"),
        "{text}"
    );
}

#[test]
fn plan_json_on_depth_from_rgb_is_deterministic_and_carries_the_true_depth_run() {
    let args = [
        "--json",
        "--category",
        "can",
        "--index",
        "1",
        "--no-physics",
    ];
    let a = plan(&args);
    let b = plan(&args);
    assert!(
        matches!(a.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&a.stderr)
    );
    assert_eq!(a.stdout, b.stdout, "the same seed gives the same bytes");
    let report: serde_json::Value = serde_json::from_slice(&a.stdout).unwrap();
    assert_eq!(report["depth_from"], "baseline");
    assert_eq!(report["plan"]["views"].as_array().unwrap().len(), 5);
    let truth = &report["on_rendered_depth"];
    assert_eq!(truth["views"].as_array().unwrap().len(), 5);
    assert_eq!(
        truth["cameras"], report["plan"]["cameras"],
        "the same views"
    );
    // The multi-view stereo network instead, and what --depth-from refuses.
    let mvs = plan(&[
        "--json",
        "--category",
        "can",
        "--index",
        "1",
        "--no-physics",
        "--depth-from",
        "mvs",
    ]);
    let report: serde_json::Value = serde_json::from_slice(&mvs.stdout).unwrap();
    assert_eq!(report["depth_from"], "mvs");
    for (args, says) in [
        (
            &["--depth-from", "stereo"][..],
            "expected baseline, refined, mvs or lsm, or rendered",
        ),
        (
            &["--depth-from", "lsm", "--views", "1"][..],
            "at least 2 views to predict depth",
        ),
    ] {
        let out = plan(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(
            err.contains(says) && err.trim_end().lines().count() == 1,
            "{args:?}: {err}"
        );
    }
}

#[test]
fn plan_json_is_complete_and_deterministic() {
    let args = [
        "--json",
        "--category",
        "box",
        "--index",
        "0",
        "--model",
        "gqcnn_small_multiview",
        "--views",
        "4",
        "--depth-from",
        "rendered",
    ];
    let a = plan(&args);
    let b = plan(&args);
    assert!(a.status.success(), "{}", String::from_utf8_lossy(&a.stderr));
    assert_eq!(a.stdout, b.stdout, "the same seed gives the same bytes");
    let report: serde_json::Value = serde_json::from_slice(&a.stdout).unwrap();
    assert_eq!(report["model"], "gqcnn_small_multiview");
    let plan = &report["plan"];
    assert_eq!(plan["views"].as_array().unwrap().len(), 4);
    assert_eq!(plan["cameras"].as_array().unwrap().len(), 4);
    let quality = plan["best"]["quality"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&quality), "{quality}");
    assert_eq!(plan["top"][0], plan["best"]);
    assert!(plan["physics"]["success"].is_boolean());
    assert!(plan["analytic"]["robust_epsilon"].as_f64().unwrap() >= 0.0);
    let report = &report["object"];
    assert_eq!(report["training_views"].as_array().unwrap().len(), 20);
    assert_eq!(report["test_views"].as_array().unwrap().len(), 10);
    let poses = report["stable_poses"].as_array().unwrap();
    assert!(poses.len() >= 2, "a box rests on several faces");
    let sum: f64 = poses
        .iter()
        .map(|p| p["probability"].as_f64().unwrap())
        .sum();
    assert!(sum > 0.9 && sum <= 1.0001, "{sum}");
}

#[test]
fn plan_fuse_fuses_five_views_rescores_and_is_deterministic() {
    let args = [
        "--json",
        "--fuse",
        "--category",
        "can",
        "--index",
        "1",
        "--depth-from",
        "rendered",
    ];
    let a = plan(&args);
    let b = plan(&args);
    assert!(a.status.success(), "{}", String::from_utf8_lossy(&a.stderr));
    assert_eq!(a.stdout, b.stdout, "the same seed gives the same bytes");
    let report: serde_json::Value = serde_json::from_slice(&a.stdout).unwrap();
    // The multi-view GQ-CNN proposes in 5 views, the first straight down.
    assert_eq!(report["model"], "gqcnn_small_multiview");
    let plan = &report["plan"];
    assert_eq!(plan["views"].as_array().unwrap().len(), 5);
    assert!((plan["views"][0]["elevation_deg"].as_f64().unwrap() - 90.0).abs() < 1e-3);
    // The best ten were re-scored on virtual views: each keeps the score it was planned with.
    let top = plan["top"].as_array().unwrap();
    assert_eq!(top.len(), 10);
    for g in top {
        assert!(g["view_quality"].as_f64().is_some(), "{g}");
    }
    let scores: Vec<f64> = top.iter().map(|g| g["quality"].as_f64().unwrap()).collect();
    assert!(scores.windows(2).all(|w| w[0] >= w[1]), "{scores:?}");
    // The summary says which planner ran.
    let text = plan_text(&[
        "--fuse",
        "--category",
        "can",
        "--index",
        "1",
        "--no-physics",
        "--depth-from",
        "rendered",
    ]);
    assert!(
        text.contains("the multi-view planner: the views fused"),
        "{text}"
    );
    assert!(text.contains("5 view(s) 0.65 m away"), "{text}");
}

fn plan_text(args: &[&str]) -> String {
    let out = plan(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// A 17 x 13 cm box lying flat, 3.8 cm tall: too wide for the Panda from above, too low to take
/// from the side without a finger in the table. The multi-view GQ-CNN planning in each view on
/// its own returns no grasp and says why.
#[test]
fn plan_says_why_it_returns_no_grasp() {
    let out = plan(&[
        "--category",
        "box",
        "--index",
        "2",
        "--model",
        "gqcnn_small_multiview",
        "--no-fuse",
        "--views",
        "4",
        "--depth-from",
        "rendered",
    ]);
    // No grasp is a result, not an error: exit code 3.
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("no grasp: every candidate was rejected: the open hand meets observed depth"),
        "{text}"
    );
}

/// The default run's grasp carries its chance to hold (the multi-view planner's ranker, mapped; with
/// `--no-fuse` the top-down GQ-CNN's mapped quality); `--min-probability` above it answers no
/// grasp (exit code 3) with that chance, at 0 the grasp is returned.
#[test]
fn plan_answers_no_grasp_below_the_chance_asked_for() {
    for (planner, model) in [
        (&[][..], "models/probability_fused.json"),
        (&["--no-fuse"][..], "models/probability_topdown.json"),
    ] {
        let args = |more: &[&'static str]| [&["--no-physics"][..], planner, more].concat();
        let text = plan_text(&args(&[]));
        let line = text
            .lines()
            .find(|l| l.starts_with("chance to hold: "))
            .unwrap_or_else(|| panic!("{text}"));
        assert!(line.contains(model), "{line}");
        let chance: f32 = line["chance to hold: ".len()..][..4].parse().unwrap();
        assert!((0.0..=1.0).contains(&chance), "{line}");
        assert!(plan_text(&args(&["--min-probability", "0"])).contains(line));
        let above = format!("{:.2}", (chance + 0.01).min(1.0));
        let out = plan(&[&args(&[])[..], &["--min-probability", above.as_str()]].concat());
        assert_eq!(out.status.code(), Some(3), "{planner:?}");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains(&format!(
                "no grasp reaches a chance of {above} to hold: the best's is {chance:.2}"
            )),
            "{text}"
        );
    }
}

#[test]
fn plan_reports_bad_input_in_one_line_and_exits_2() {
    for args in [
        &["--mesh", "/nonexistent/thing.obj"][..],
        &["--category", "spaceship"][..],
        &["--camera", "kinect"][..],
        &["--mesh", "Cargo.toml"][..],
        &["--model", "no_such_network"][..],
        &["--model", "/nonexistent/net.json"][..],
        &["--views", "0"][..],
        &["--views", "11"][..],
        &["--distance-m", "0"][..],
        &["--min-probability", "1.5"][..],
        &["--no-fuse", "--cem", "--min-probability", "0.5"][..],
    ] {
        let out = plan(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(
            err.starts_with("error: ") && err.trim_end().lines().count() == 1,
            "{args:?}: {err}"
        );
    }
}

#[test]
fn plan_describes_a_real_mesh_when_the_shared_data_is_there() {
    let Some(mesh) = shared_data("meshes/ycb/meshes/005_tomato_soup_can_textured.obj") else {
        return;
    };
    let out = plan(&["--mesh", mesh.to_str().unwrap()]);
    assert!(
        matches!(out.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("marginal"), "the can's side rolls: {text}");
}

#[test]
fn objects_writes_meshes_and_a_manifest_the_same_bytes_twice() {
    let dir = tempfile::tempdir().unwrap();
    let run = |out: &std::path::Path| {
        let status = Command::new(env!("CARGO_BIN_EXE_objects"))
            .args([
                "--per-category",
                "1",
                "--seed",
                "3",
                "--categories",
                "can,box",
                "--cell-mm",
                "4",
            ])
            .arg("--out")
            .arg(out)
            .output()
            .unwrap();
        assert!(
            status.status.success(),
            "{}",
            String::from_utf8_lossy(&status.stderr)
        );
    };
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    run(&a);
    run(&b);
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("manifest.json")).unwrap()).unwrap();
    let objects = manifest["objects"].as_array().unwrap();
    assert_eq!(objects.len(), 2);
    for entry in objects {
        let file = entry["file"].as_str().unwrap();
        let mesh = mvgrasp::geometry::load_mesh(a.join(file)).unwrap();
        assert!(mesh.is_watertight(), "{file}");
        assert_eq!(
            mesh.triangles().len() as u64,
            entry["triangles"].as_u64().unwrap()
        );
        assert_eq!(
            std::fs::read(a.join(file)).unwrap(),
            std::fs::read(b.join(file)).unwrap()
        );
    }
    let bad = Command::new(env!("CARGO_BIN_EXE_objects"))
        .args(["--out", "/proc/forbidden", "--per-category", "1"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
}

fn grasps(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_grasps"))
        .args(args)
        .output()
        .expect("run grasps")
}

#[test]
fn grasps_samples_scores_simulates_and_writes_the_same_json_twice() {
    let dir = tempfile::tempdir().unwrap();
    let run = |out: &std::path::Path| {
        let output = grasps(&["--n", "12", "--out", out.to_str().unwrap()]);
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        std::fs::read_to_string(out.join("grasps.json")).unwrap()
    };
    let first = run(&dir.path().join("a"));
    let again = run(&dir.path().join("b"));
    assert_eq!(first, again, "same seed, same bytes");
    let json: serde_json::Value = serde_json::from_str(&first).unwrap();
    let list = json["analysis"]["grasps"].as_array().unwrap();
    assert_eq!(list.len(), 12);
    let mut previous = f64::INFINITY;
    for g in list {
        let robust = g["quality"]["robust_epsilon"].as_f64().unwrap();
        assert!(robust <= previous, "sorted by robust epsilon");
        previous = robust;
        assert!(g["physics"]["success"].is_boolean());
        // The grasp centre is above the table, in the world frame.
        assert!(g["grasp"]["world_from_gripper"][2][3].as_f64().unwrap() > 0.0);
    }
}

#[test]
fn grasps_reports_bad_input_in_one_line_and_exits_2() {
    for (args, needle) in [
        (vec!["--gripper", "barrett"], "--gripper"),
        (vec!["--pose", "99"], "--pose 99"),
        (vec!["--mesh", "/nonexistent/x.obj"], "/nonexistent/x.obj"),
    ] {
        let output = grasps(&args);
        assert_eq!(output.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(
            stderr.starts_with("error: ") && stderr.contains(needle),
            "{stderr}"
        );
    }
}

/// The promise of the README's first command: from RGB alone, the default run's grasp on its
/// default object holds in the project's trial; and over ten seeds of its views and colours the
/// grasps planned on the RGB views' depth hold as often as those planned on a depth camera's
/// (the rendered depth, the same run), within one. (Measured: 7 of 10 on the RGB views' depth, 8
/// of 10 on the rendered depth; the sweep that compared absolute colours held 4 of 10.)
#[test]
fn the_default_run_from_rgb_holds_as_often_as_on_a_depth_camera() {
    const HELD: &str = "held in physics";
    let (mut on_rgb, mut on_depth) = (0, 0);
    for seed in 0..10 {
        let out = plan(&["--seed", &seed.to_string()]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8(out.stdout).unwrap();
        let chosen = text.contains("physics (rapier: close, lift, shake): held");
        assert!(chosen || seed != 0, "seed 0, the README's run: {text}");
        // "on the rendered (true) depth, the same run: ..., held in physics (on the predicted
        // depth: ...)"
        let line = text
            .lines()
            .find(|l| l.starts_with("on the rendered (true) depth"))
            .unwrap_or_else(|| panic!("seed {seed}: no comparison line in {text}"));
        let (truth, predicted) = line.split_once("(on the predicted depth").unwrap();
        assert_eq!(predicted.contains(HELD), chosen, "{line}");
        on_rgb += usize::from(chosen);
        on_depth += usize::from(truth.contains(HELD));
    }
    assert!(
        on_rgb + 1 >= on_depth,
        "held on the RGB views' depth {on_rgb} of 10, on the rendered depth {on_depth} of 10"
    );
}
