//! `evaluate`: the report from records, the same bytes whether a run was interrupted or not,
//! and clear refusals.

use std::path::{Path, PathBuf};

use mvgrasp::evaluate::{EvalConfig, Progress, RunOptions, Shard, evaluate, evaluate_with};
use mvgrasp::geometry::objects::{Category, generate};
use mvgrasp::geometry::write_obj;

struct Quiet;

impl Progress for Quiet {
    fn step(&mut self, _: usize, _: usize, _: &str) {}
}

/// Two small built-in objects as mesh files in `dir/meshes`, and a config that plans on them
/// with the depth planner, two seeds and the exhaustive search, predicts their depth from
/// 1 and 2 views, clears a packed, a pile and a bin scene of two of them from one Primesense
/// view 0.6 m away, and judges 3 grasps' labels on each.
fn two_objects(dir: &Path) -> EvalConfig {
    let meshes = dir.join("meshes");
    std::fs::create_dir_all(&meshes).unwrap();
    for (category, index) in [(Category::Can, 30), (Category::Box, 31)] {
        let object = generate(category, index, 0).unwrap();
        write_obj(&object.mesh, meshes.join(format!("{}.obj", object.name))).unwrap();
    }
    EvalConfig {
        sets: vec![format!("folder:{}", meshes.display())],
        per_category: 0,
        data: PathBuf::from("/nonexistent"),
        max_meshes: 0,
        policies: vec!["depth".into()],
        seeds: vec![0, 1],
        all_poses: false,
        coverage: true,
        suites: vec![
            "grasps".into(),
            "depth".into(),
            "clutter".into(),
            "labels".into(),
        ],
        depth_views: vec![1, 2],
        depth_distance_m: 0.5,
        depth_photo: false,
        clutter_scenes: vec!["packed".into(), "pile".into(), "bin".into()],
        clutter_views: vec![1],
        clutter_rounds: 1,
        clutter_objects: 2,
        clutter_camera: "primesense".into(),
        clutter_distance_m: 0.6,
        clutter_training_depths: true,
        clutter_depth_from: None,
        label_grasps: 3,
        label_trials: 3,
        label_outcome_trials: 4,
        speed_runs: 1,
    }
}

fn files(out: &Path) -> Vec<(String, Vec<u8>)> {
    let mut names = vec![
        "results.json".to_string(),
        "report.md".into(),
        "report.html".into(),
    ];
    let mut pictures: Vec<String> = std::fs::read_dir(out.join("pictures"))
        .unwrap()
        .map(|e| format!("pictures/{}", e.unwrap().file_name().to_string_lossy()))
        .collect();
    pictures.sort();
    names.extend(pictures);
    names
        .into_iter()
        .map(|n| {
            let bytes = std::fs::read(out.join(&n)).unwrap();
            (n, bytes)
        })
        .collect()
}

#[test]
fn a_run_interrupted_and_resumed_writes_the_same_bytes_as_one_that_was_not() {
    if crate::common::renderer().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let config = two_objects(dir.path());
    let whole = dir.path().join("whole");
    let results = evaluate(&config, &whole, &mut Quiet).unwrap();
    assert_eq!(results.objects.len(), 2, "{:?}", results.skipped);
    assert_eq!(results.grasps.len(), 4);
    assert!(results.objects.iter().all(|p| p.holdable.is_some()));
    let report = std::fs::read_to_string(whole.join("report.md")).unwrap();
    assert!(
        report.contains("| depth | `plan --no-fuse --depth-from rendered` | the top-down GQ-CNN on a perfect depth camera | folder:"),
        "{report}"
    );

    // The interrupted run: its records up to the middle of the second object, the last line
    // cut short; no report, no pictures.
    let resumed = dir.path().join("resumed");
    std::fs::create_dir_all(&resumed).unwrap();
    std::fs::copy(whole.join("config.json"), resumed.join("config.json")).unwrap();
    let records = std::fs::read_to_string(whole.join("records.jsonl")).unwrap();
    let lines: Vec<&str> = records.lines().collect();
    assert_eq!(
        lines.len(),
        2 * (1 + 2 + 1 + 1) + 3,
        "per object: its poses, a grasp per seed, its depth, its labels; a round per clutter scene"
    );
    assert!(!results.labels.is_empty());
    assert!(report.contains("## Labels"), "{report}");
    assert_eq!(results.clutter.len(), 3, "{:?}", results.skipped);
    assert!(
        results.clutter.iter().all(|r| !r.attempts.is_empty()),
        "{:?}",
        results.clutter
    );
    assert!(report.contains("## Clutter"), "{report}");
    let mut kept = lines[..6].join("\n");
    kept.push('\n');
    kept.push_str(&lines[6][..lines[6].len() / 2]);
    std::fs::write(resumed.join("records.jsonl"), kept).unwrap();
    evaluate(&config, &resumed, &mut Quiet).unwrap();
    for ((name, a), (_, b)) in files(&whole).iter().zip(files(&resumed)) {
        assert!(*a == b, "{name} differs after resuming");
    }
    assert_eq!(files(&whole).len(), files(&resumed).len());
}

#[test]
fn a_folder_of_another_runs_settings_and_an_unknown_policy_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("config.json"), "{}").unwrap();
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_evaluate"))
            .args(args)
            .args(["--plain", "--data", "/nonexistent"])
            .output()
            .unwrap()
    };
    let other = run(&["--out", out.to_str().unwrap(), "--set", "held-out"]);
    let message = String::from_utf8_lossy(&other.stderr);
    assert_eq!(other.status.code(), Some(2), "{message}");
    assert!(
        message.contains("config.json: this folder holds a run with other settings"),
        "{message}"
    );
    let unknown = run(&[
        "--out",
        dir.path().join("x").to_str().unwrap(),
        "--policy",
        "sweep",
    ]);
    let message = String::from_utf8_lossy(&unknown.stderr);
    assert_eq!(unknown.status.code(), Some(2), "{message}");
    assert!(
        message.contains("--policy sweep: expected one of rgb, depth"),
        "{message}"
    );
    for (flag, value, expected) in [
        (
            "--clutter-scene",
            "tote",
            "clutter scene \"tote\": expected one of packed, pile, bin",
        ),
        ("--clutter-views", "0", "clutter views 0: expected 1 to 9"),
        (
            "--clutter-distance-m",
            "3",
            "clutter distance 3 m: expected 0.3 to 1.5",
        ),
        (
            "--clutter-objects",
            "0",
            "clutter objects 0: a round needs at least one",
        ),
        (
            "--label-outcome-trials",
            "0",
            "labels: grasps, trials and outcome trials must each be at least 1",
        ),
        (
            "--clutter-depth-from",
            "baseline",
            "clutter views 1 with depth from RGB (baseline): predicting depth needs at least 2 views",
        ),
        (
            "--clutter-depth-from",
            "sweep",
            "clutter depth from \"sweep\", expected baseline, refined, mvs or lsm",
        ),
    ] {
        // Two share a folder: a refused run writes no settings there.
        let refused = run(&[
            "--out",
            dir.path().join(value).to_str().unwrap(),
            "--suite",
            "clutter",
            flag,
            value,
        ]);
        let message = String::from_utf8_lossy(&refused.stderr);
        assert_eq!(refused.status.code(), Some(2), "{message}");
        assert!(message.contains(expected), "{flag}: {message}");
    }
}

#[test]
fn clutter_rounds_plan_on_depth_predicted_from_colour_views() {
    if crate::common::renderer().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let config = EvalConfig {
        suites: vec!["clutter".into()],
        clutter_scenes: vec!["packed".into(), "bin".into()],
        clutter_views: vec![3],
        clutter_depth_from: Some("baseline".into()),
        clutter_camera: "phoxi_s".into(),
        clutter_distance_m: 0.7,
        clutter_training_depths: false,
        ..two_objects(dir.path())
    };
    let out = dir.path().join("rgb");
    let results = evaluate(&config, &out, &mut Quiet).unwrap();
    assert_eq!(results.clutter.len(), 2, "{:?}", results.skipped);
    // The sweep's depth is good enough to plan on, in the bin too (its walls at their known
    // depth): each round tries grasps, and some hold.
    for round in &results.clutter {
        assert_eq!(round.depth_from.as_deref(), Some("baseline"));
        assert!(round.tried() > 0, "{round:?}");
    }
    assert!(
        results.clutter.iter().any(|r| r.held() > 0),
        "{:?}",
        results.clutter
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("| packed | 3 | phoxi_s 0.70 m | RGB, baseline | 1 |"),
        "{report}"
    );
}

#[test]
fn labels_copied_from_a_run_of_other_settings_are_made_again() {
    let dir = tempfile::tempdir().unwrap();
    let config = EvalConfig {
        suites: vec!["labels".into()],
        ..two_objects(dir.path())
    };
    let first = dir.path().join("first");
    let before = evaluate(&config, &first, &mut Quiet).unwrap();
    assert!(!before.labels.is_empty(), "{:?}", before.skipped);
    let other = EvalConfig {
        label_grasps: 1,
        ..config
    };
    let second = dir.path().join("second");
    std::fs::create_dir_all(&second).unwrap();
    std::fs::copy(first.join("records.jsonl"), second.join("records.jsonl")).unwrap();
    let after = evaluate(&other, &second, &mut Quiet).unwrap();
    let mut per_object = std::collections::BTreeMap::<&str, usize>::new();
    for r in &after.labels {
        *per_object.entry(r.object.as_str()).or_default() += 1;
    }
    assert!(
        !per_object.is_empty() && per_object.values().all(|&n| n == 1),
        "{per_object:?}"
    );
}

#[test]
fn the_speed_suite_times_every_stage_and_network_and_keeps_its_figures_when_resumed() {
    if crate::common::renderer().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let config = EvalConfig {
        suites: vec!["speed".into()],
        policies: vec!["depth".into(), "rgb-fused".into()],
        speed_runs: 2,
        ..two_objects(dir.path())
    };
    let out = dir.path().join("speed");
    let results = evaluate(&config, &out, &mut Quiet).unwrap();
    let speed = results.speed.expect("the speed suite's record");
    assert_eq!((speed.runs, speed.threads > 0), (2, true));
    let names: Vec<&str> = speed.stages.iter().map(|s| s.policy.as_str()).collect();
    assert_eq!(names, ["depth", "rgb-fused"]);
    for s in &speed.stages {
        assert!(
            s.render_ms > 0.0 && s.plan_ms > 0.0 && s.check_ms > 0.0,
            "{s:?}"
        );
        let parts = s.render_ms + s.depth_ms + s.plan_ms + s.fuse_ms + s.check_ms;
        // Medians of parts need not add up to the median of sums, but not far off.
        assert!((0.5..2.0).contains(&(parts / s.total_ms)), "{s:?}");
    }
    let (depth, rgb) = (&speed.stages[0], &speed.stages[1]);
    // The top-down planner on rendered depth predicts nothing and fuses nothing (its fusion
    // timer runs around no work); the default run does both.
    assert!(depth.depth_ms == 0.0 && depth.fuse_ms < 1.0, "{depth:?}");
    assert!(rgb.depth_ms > 1.0 && rgb.fuse_ms > 1.0, "{rgb:?}");
    for network in ["gqcnn_small_topdown", "gqcnn_small_multiview"] {
        let ours: Vec<_> = speed
            .networks
            .iter()
            .filter(|n| n.network == network && n.runtime == "mvgrasp")
            .collect();
        assert_eq!(ours.len(), 2, "{:?}", speed.networks);
        assert!(
            ours.iter()
                .all(|n| n.crops_per_s > 0.0 && n.median_ms > 0.0)
        );
        // Where torch ran, it scored the same crops alike.
        for theirs in speed
            .networks
            .iter()
            .filter(|n| n.network == network && n.runtime != "mvgrasp")
        {
            let mine = ours.iter().find(|n| n.batch == theirs.batch).unwrap();
            assert!(
                (mine.mean_p - theirs.mean_p).abs() < 1e-4,
                "{mine:?} {theirs:?}"
            );
        }
    }
    // Where torch installs (as .ci/run installs it) its rows are there: 2 runtimes x 2
    // batches of each network.
    if speed.peer.starts_with("torch did not run") {
        eprintln!("no torch peer: {}", speed.peer);
    } else {
        assert!(speed.peer.starts_with("torch "), "{}", speed.peer);
        let theirs = speed.networks.iter().filter(|n| n.runtime != "mvgrasp");
        assert_eq!(theirs.count(), 8, "{:?}", speed.networks);
    }
    let report = std::fs::read(out.join("report.md")).unwrap();
    assert!(String::from_utf8_lossy(&report).contains("## Speed"));
    // Run again: the recorded figures, not new ones.
    evaluate(&config, &out, &mut Quiet).unwrap();
    assert_eq!(std::fs::read(out.join("report.md")).unwrap(), report);
}

#[test]
fn the_depth_suite_scores_every_method_and_tallies_the_confidence_of_the_networks() {
    if crate::common::renderer().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let flat = EvalConfig {
        suites: vec!["depth".into()],
        depth_views: vec![2],
        ..two_objects(dir.path())
    };
    let first = dir.path().join("flat");
    let results = evaluate(&flat, &first, &mut Quiet).unwrap();
    assert_eq!(results.depth.len(), 2, "{:?}", results.skipped);
    for record in &results.depth {
        let methods: Vec<&str> = record.methods.iter().map(|(m, ..)| m.as_str()).collect();
        assert_eq!(
            methods,
            ["lsm", "mvs", "refined", "sweep", "sweep-hull", "hull"]
        );
        for (method, bins) in &record.reliability {
            let (_, _, all) = record.methods.iter().find(|(m, ..)| m == method).unwrap();
            // Every object pixel lands in one tenth, and its within-5 mm count is the method's.
            let pixels: u64 = bins.iter().map(|b| b[0]).sum();
            let good: u64 = bins.iter().map(|b| b[1]).sum();
            assert_eq!(
                (pixels, good),
                (all.object_pixels, all.within_5mm),
                "{method}"
            );
        }
        let confident: Vec<&str> = record.reliability.iter().map(|(m, _)| m.as_str()).collect();
        assert_eq!(confident, ["mvs", "refined"]);
    }
    let report = std::fs::read_to_string(first.join("report.md")).unwrap();
    assert!(
        report.contains("| refined | 2 |") && report.contains("Reliability"),
        "{report}"
    );
    // The first object's error sheet, named in the report.
    let sheets: Vec<String> = std::fs::read_dir(first.join("pictures"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("depth_"))
        .collect();
    assert_eq!(sheets.len(), 1, "{sheets:?}");
    assert!(
        report.contains(&format!("(pictures/{})", sheets[0])),
        "{report}"
    );

    // The photographic look: records copied from the flat run are not taken for its own.
    let photo = EvalConfig {
        depth_photo: true,
        ..flat
    };
    let second = dir.path().join("photo");
    std::fs::create_dir_all(&second).unwrap();
    std::fs::copy(first.join("records.jsonl"), second.join("records.jsonl")).unwrap();
    let photographed = evaluate(&photo, &second, &mut Quiet).unwrap();
    assert_eq!(photographed.depth.len(), 2, "{:?}", photographed.skipped);
    assert_ne!(photographed.depth, results.depth);
    let report = std::fs::read_to_string(second.join("report.md")).unwrap();
    assert!(report.contains("the photographic look"), "{report}");
}

#[test]
fn objects_shared_by_threads_or_machines_give_the_same_bytes_as_one_after_the_other() {
    if crate::common::renderer().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let config = EvalConfig {
        suites: vec!["grasps".into(), "depth".into()],
        seeds: vec![0],
        coverage: false,
        depth_views: vec![2],
        ..two_objects(dir.path())
    };
    let one = dir.path().join("one");
    let results = evaluate(&config, &one, &mut Quiet).unwrap();
    assert_eq!(
        (results.objects.len(), results.depth.len()),
        (2, 2),
        "{:?}",
        results.skipped
    );
    let three = dir.path().join("three");
    let jobs = |jobs, shard| RunOptions { jobs, shard };
    evaluate_with(&config, &three, &mut Quiet, jobs(3, None)).unwrap();
    assert_eq!(files(&three), files(&one));

    // Spread over two machines sharing the folder: each shard records its half and writes no
    // report; the run without a shard takes both halves and writes the same bytes.
    let spread = dir.path().join("spread");
    for index in 0..2 {
        let shard = Shard { index, count: 2 };
        let part = evaluate_with(&config, &spread, &mut Quiet, jobs(1, Some(shard))).unwrap();
        assert_eq!(part.depth.len(), 1, "{:?}", part.skipped);
        assert!(!spread.join("report.md").exists());
        assert!(spread.join(format!("shards/{index}-of-2.jsonl")).is_file());
    }
    evaluate_with(&config, &spread, &mut Quiet, jobs(1, None)).unwrap();
    // Nothing was left to do: the folder's own journal stayed empty.
    assert_eq!(
        std::fs::read_to_string(spread.join("records.jsonl")).unwrap(),
        ""
    );
    assert_eq!(files(&spread), files(&one));
    assert!("2/2".parse::<Shard>().is_err() && "1/2".parse::<Shard>().is_ok());
}

#[test]
fn the_depth_suite_scores_real_photographs_against_the_sensors_depth() {
    let Some(dir) = crate::shared_data::shared_data("real_rgb/apc_shelf_bin") else {
        return;
    };
    let suite = mvgrasp::evaluate::depth::DepthSuite::new(0.5, false).unwrap();
    let out = tempfile::tempdir().unwrap();
    let sheet = out.path().join("sheet.png");
    let records = suite
        .run_photographs("apc_shelf_bin", &dir, &[1, 2], Some((&sheet, 2)))
        .unwrap();
    let views: Vec<usize> = records.iter().map(|r| r.views).collect();
    assert_eq!(views, [1, 2]);
    // One view: only the LSM takes one, and it cannot place its grid from a camera that does
    // not look down; the record says so by holding no method.
    assert!(records[0].methods.is_empty(), "{:?}", records[0].methods);
    // The error sheet: 2 columns and 6 methods', each the objects' box (at least 64 pixels),
    // in 2 rows.
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&sheet).unwrap(),
    ));
    let info = decoder.read_info().unwrap().info().clone();
    assert_eq!((info.width % 8, info.height % 2), (0, 0));
    assert!(info.width / 8 >= 64 && info.height / 2 >= 64, "{info:?}");
    let two = &records[1];
    assert_eq!(two.set, mvgrasp::evaluate::depth::REAL_PHOTOS);
    let (_, first, all) = two.methods.iter().find(|(m, ..)| m == "sweep").unwrap();
    // Two views' masked pixels with sensor depth, the first view's among them; the sweep
    // confirms only some of them.
    assert!(all.object_pixels > first.object_pixels && first.object_pixels > 1000);
    assert!((0.01..0.99).contains(&all.predicted_share()), "{all:?}");
    for (method, bins) in &two.reliability {
        let (_, _, all) = two.methods.iter().find(|(m, ..)| m == method).unwrap();
        assert_eq!(bins.iter().map(|b| b[0]).sum::<u64>(), all.object_pixels);
    }
}
