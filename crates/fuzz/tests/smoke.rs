//! The CI pass: every target fuzzed for a few seconds (`MVGRASP_FUZZ_SECONDS`, default 3),
//! and every committed regression input replayed with every check.

use std::time::Duration;

use mvgrasp_fuzz::{TARGETS, check_one, fuzz, regression_inputs, regressions_dir, work_folder};

fn seconds() -> u64 {
    std::env::var("MVGRASP_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3)
}

#[test]
fn every_target_survives_a_short_fuzz_pass() {
    let parent = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for target in TARGETS {
        let work = work_folder(parent.path(), target).unwrap();
        let summary = fuzz(
            target,
            &work,
            Duration::from_secs(seconds()),
            1,
            Vec::new(),
            |_| {},
        );
        assert!(summary.executions > 0, "{}: nothing ran", target.name);
        // The seeds are valid files: a target that accepts nothing tests only its first check.
        if summary.accepted == 0 {
            let refusals: Vec<String> = (target.seeds)()
                .iter()
                .map(|seed| format!("{:?}", check_one(target, &work, seed)))
                .collect();
            failures.push(format!(
                "{}: accepted no seed: {}",
                target.name,
                refusals.join("; ")
            ));
        }
        for finding in summary.findings {
            failures.push(format!(
                "{}: {} (input {:?})",
                target.name,
                finding.problem,
                String::from_utf8_lossy(&finding.input[..finding.input.len().min(200)])
            ));
        }
    }
    assert!(failures.is_empty(), "findings:\n{}", failures.join("\n"));
}

#[test]
fn every_regression_input_passes_every_check() {
    let parent = tempfile::tempdir().unwrap();
    let root = regressions_dir();
    let mut replayed = 0;
    for target in TARGETS {
        let work = work_folder(parent.path(), target).unwrap();
        for file in regression_inputs(&root, target.name) {
            let input = std::fs::read(&file).unwrap();
            if let Err(problem) = check_one(target, &work, &input) {
                panic!("{}: {problem}", file.display());
            }
            replayed += 1;
        }
    }
    // Folders under regressions/ must be targets (a renamed target would skip its inputs).
    for entry in std::fs::read_dir(&root).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().to_string();
        assert!(
            TARGETS.iter().any(|t| t.name == name) || name.starts_with('.') || name == "README.md",
            "regressions/{name} is not a target"
        );
    }
    eprintln!("replayed {replayed} regression inputs");
}
