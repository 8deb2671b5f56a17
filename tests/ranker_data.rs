//! `ranker_data`: the multi-view planner's re-scored candidates, each tried in the trial, and
//! a run that resumes from its records with the same bytes.

use std::process::Command;

use mvgrasp::geometry::objects::{Category, generate};
use mvgrasp::geometry::write_obj;
use mvgrasp::ranker_data::RankerData;

#[test]
fn every_rescored_candidate_is_tried_in_the_order_of_its_rescore() {
    let Some(renderer) = crate::common::renderer() else {
        return;
    };
    let object = generate(Category::Box, 60, 0).unwrap();
    for ranked in [false, true] {
        let samples = RankerData::new(ranked)
            .unwrap()
            .samples(&renderer, &object.name, &object.mesh)
            .unwrap();
        assert!(samples.len() >= 10, "{} candidates", samples.len());
        for (i, s) in samples.iter().enumerate() {
            assert_eq!((s.rank, s.object.as_str()), (i, object.name.as_str()));
            assert!(s.view_quality.is_some() && s.held.is_some(), "{s:?}");
            assert!(
                (0.0..=90.0).contains(&s.tilt_deg) && s.width_m > 0.0,
                "{s:?}"
            );
            // A ranker orders by its chance and keeps the re-score beside it.
            assert_eq!(s.virtual_quality.is_some(), ranked, "{s:?}");
        }
        if !ranked {
            // Unranked, the candidates come in the re-score's order.
            assert!(samples.windows(2).all(|w| w[0].quality >= w[1].quality));
        }
    }
}

#[test]
fn an_interrupted_run_resumes_and_writes_the_same_bytes() {
    if crate::common::renderer().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let meshes = dir.path().join("meshes");
    std::fs::create_dir_all(&meshes).unwrap();
    for (category, index) in [(Category::Can, 61), (Category::Box, 61)] {
        let object = generate(category, index, 0).unwrap();
        write_obj(&object.mesh, meshes.join(format!("{}.obj", object.name))).unwrap();
    }
    let run = |out: &std::path::Path| {
        let output = Command::new(env!("CARGO_BIN_EXE_ranker_data"))
            .args(["--out", out.to_str().unwrap()])
            .args(["--set", &format!("folder:{}", meshes.display())])
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        std::fs::read(out.join("rescored.jsonl")).unwrap()
    };
    let whole = dir.path().join("whole");
    let bytes = run(&whole);
    let lines = String::from_utf8(bytes.clone()).unwrap();
    assert!(lines.lines().count() >= 20);
    assert!(lines.contains("can_061.obj") && lines.contains("box_061.obj"));
    // The first object's record and half of the second's: the second is made again.
    let records = std::fs::read_to_string(whole.join("records.jsonl")).unwrap();
    let kept: Vec<&str> = records.lines().collect();
    assert_eq!(kept.len(), 2);
    let resumed = dir.path().join("resumed");
    std::fs::create_dir_all(&resumed).unwrap();
    std::fs::write(
        resumed.join("records.jsonl"),
        format!("{}\n{}", kept[0], &kept[1][..kept[1].len() / 2]),
    )
    .unwrap();
    assert_eq!(run(&resumed), bytes);

    let refused = Command::new(env!("CARGO_BIN_EXE_ranker_data"))
        .args([
            "--out",
            dir.path().join("x").to_str().unwrap(),
            "--set",
            "heldout",
        ])
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--set \"heldout\": expected"));
}
