//! The tables of the depth, clutter and labels suites.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::{pct, wilson_95};
use crate::evaluate::Results;
use crate::evaluate::depth::DepthRecord;

/// The depth suite's tables: per set, the seed paper's Table 1 layout for every method.
pub(super) fn depth_tables(md: &mut String, results: &Results) {
    use crate::evaluate::depth::{DepthErrors, METHODS};
    let _ = writeln!(
        md,
        "## Depth from RGB\n\nDepth predicted from the first N of the seed paper's 10 test views \
         ({:.2} m away, the first top-down; {}, masks given) against the rendered \
         depth, over the object's pixels: the median and mean error of the predicted pixels \
         (mm), the share of object pixels predicted, the share within 5 mm (a missing pixel is \
         not within), and the paper's normalised error (mean error over mean true depth). \
         `sweep`: the plane sweep as `plan --rgb` uses it (unconfirmed pixels missing); \
         `sweep-hull`: as the default run plans on it (unconfirmed pixels at the visual hull's \
         depth); `hull`: the visual hull alone; `lsm`, `mvs`: the shipped networks; \
         `refined`: the plane sweep sharpened by the shipped refiner (`mvs` and `refined` keep \
         every pixel whatever its confidence).\n",
        results.config.depth_distance_m,
        if results.config.depth_photo {
            "the photographic look"
        } else {
            "random colours"
        }
    );
    let mut sets: Vec<&str> = results.depth.iter().map(|r| r.set.as_str()).collect();
    sets.dedup();
    for set in sets {
        let records: Vec<_> = results.depth.iter().filter(|r| r.set == set).collect();
        let objects = records
            .iter()
            .map(|r| r.object.as_str())
            .collect::<std::collections::BTreeSet<_>>()
            .len();
        if set == crate::evaluate::depth::REAL_PHOTOS {
            let _ = writeln!(
                md,
                "### {set} ({objects} folders of `real_rgb`)\n\nCalibrated photographs with a \
                 depth sensor's images beside the shared meshes: each folder's first N views, its \
                 object masks given, against the sensor's depth over the masked pixels where it \
                 has depth; the folder's first view in the top-down view's columns.\n"
            );
        } else {
            let _ = writeln!(md, "### {set} ({objects} objects)\n");
        }
        let _ = writeln!(
            md,
            "| method | views | top-down: median (mm) | mean (mm) | predicted | within 5 mm | normalised | all views: median (mm) | mean (mm) | predicted | within 5 mm | normalised |\n|---|---|---|---|---|---|---|---|---|---|---|---|"
        );
        for &n in &results.config.depth_views {
            for method in METHODS {
                let (mut top, mut all) = (DepthErrors::default(), DepthErrors::default());
                let mut found = false;
                for r in records.iter().filter(|r| r.views == n) {
                    for (m, t, a) in r.methods.iter().filter(|(m, ..)| m == method) {
                        let _ = m;
                        top.merge(t);
                        all.merge(a);
                        found = true;
                    }
                }
                if !found {
                    continue;
                }
                let cells = |e: &DepthErrors| {
                    let median = match e.median_mm() {
                        m if m.is_infinite() => "50 or more".to_string(),
                        m => format!("{m:.1}"),
                    };
                    format!(
                        "{median} | {:.1} | {:.0}% | {:.0}% | {:.4}",
                        e.mean_mm(),
                        100.0 * e.predicted_share(),
                        100.0 * e.within_5mm_share(),
                        e.normalised()
                    )
                };
                let _ = writeln!(md, "| {method} | {n} | {} | {} |", cells(&top), cells(&all));
            }
        }
        md.push('\n');
        reliability_table(md, &records, &results.config.depth_views);
        // The error sheet of the set's first object (the seed paper's Fig. 5).
        let n = crate::evaluate::depth::sheet_views(&results.config.depth_views);
        if let Some(first) = records.iter().find(|r| r.views == n) {
            let names: Vec<&str> = first.methods.iter().map(|(m, ..)| m.as_str()).collect();
            let _ = writeln!(
                md,
                "The first view of {} from {n} views (the seed paper's Fig. 5): colour, true \
                 depth, then {}; above, the depth; below, the error over the object (black \
                 within 1 mm to red at {} mm or more; blue: not predicted).\n\n![depth errors \
                 of {}](pictures/{})\n",
                first.object,
                names.join(", "),
                crate::evaluate::depth::SHEET_ERROR_MM,
                first.object,
                crate::evaluate::depth::sheet_name(&first.set, &first.object, n)
            );
        }
    }
}

/// The confidence of the networks that give one against their error: per method, number of
/// views and tenth of confidence, the object pixels (all views) and the share within 5 mm.
fn reliability_table(md: &mut String, records: &[&DepthRecord], views: &[usize]) {
    use crate::evaluate::depth::CONFIDENCE_BINS;
    // (method, views) -> per bin [pixels, within 5 mm]
    let mut tallies: BTreeMap<(String, usize), Vec<[u64; 2]>> = BTreeMap::new();
    for r in records {
        for (method, bins) in &r.reliability {
            let tally = tallies
                .entry((method.clone(), r.views))
                .or_insert_with(|| vec![[0; 2]; CONFIDENCE_BINS]);
            for (t, b) in tally.iter_mut().zip(bins) {
                t[0] += b[0];
                t[1] += b[1];
            }
        }
    }
    if tallies.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "Reliability: the networks' confidence against their error (object pixels of all views \
         per tenth of confidence: pixels, and the share within 5 mm; a calibrated confidence \
         of 0.9 has about 90% within).\n\n| method | views | {} |\n|---|---|{}",
        (0..CONFIDENCE_BINS)
            .map(|b| format!("{:.1}-{:.1}", b as f64 / 10.0, (b + 1) as f64 / 10.0))
            .collect::<Vec<_>>()
            .join(" | "),
        "---|".repeat(CONFIDENCE_BINS)
    );
    for &n in views {
        for ((method, _), bins) in tallies.iter().filter(|((_, v), _)| *v == n) {
            let cells: Vec<String> = bins
                .iter()
                .map(|&[pixels, good]| match pixels {
                    0 => "-".into(),
                    _ => format!("{} ({pixels})", pct(good as usize, pixels as usize)),
                })
                .collect();
            let _ = writeln!(md, "| {method} | {n} | {} |", cells.join(" | "));
        }
    }
    md.push('\n');
}

/// The clutter suite's table: per scene and number of views, success and cleared with their
/// intervals, how the rounds ended, and GIGA's published figures beside.
pub(super) fn clutter_table(md: &mut String, results: &Results) {
    use crate::evaluate::clutter::Outcome;
    let rounds = &results.clutter;
    let _ = writeln!(
        md,
        "## Clutter\n\nVGN and GIGA's clutter removal in mvgrasp's trial: each round sets {} \
         objects from the evaluation's sets packed side by side, dropped in a pile (the box \
         taken away) or into a bin (its walls seen and in the trial), and grasps until the table \
         is empty, two grasps in a row fail or no grasp is found, planned on rendered depth or \
         on depth predicted from colour views (the objects in random colours, the method given \
         the foreground as its masks, a bin's walls at their known depth) by the method \
         named (1 view: the top-down GQ-CNN; more: the multi-view planner fusing them), \
         without a mask, or in the bin with its inside as the workspace mask{}. Success: held \
         of grasps tried; \
         cleared: held of the objects set (less those that would not rest, taken away \
         uncounted; those that fell out of the workspace as the rest settled, and those left \
         when a round ended, count as not cleared). Intervals: Wilson, 95%, over grasps and \
         over objects (rounds are not independent draws of either). Published, in their own \
         simulator (pybullet) and objects: GIGA 87.9% success packed, 69.8% pile. Simulators \
         differ: these figures are not a ranking.\n",
        rounds.iter().map(|r| r.objects).max().unwrap_or(0),
        if results.config.clutter_training_depths {
            "; the top-down GQ-CNN's crops shown as from its training cameras' depths"
        } else {
            ""
        }
    );
    let _ = writeln!(
        md,
        "| scene | views | cameras | depth | rounds | objects | grasps | success | cleared | ended with no grasp | failures by phase | fell out | uncounted |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    let key = |r: &crate::evaluate::clutter::RoundRecord| {
        (
            r.scene,
            r.views,
            format!("{} {:.2} m", r.camera, r.distance_m),
            r.depth_from
                .as_ref()
                .map_or_else(|| "rendered".to_string(), |m| format!("RGB, {m}")),
        )
    };
    let mut keys: Vec<_> = rounds.iter().map(key).collect();
    keys.sort();
    keys.dedup();
    for k in keys {
        let of: Vec<_> = rounds.iter().filter(|r| key(r) == k).collect();
        let (scene, views, cameras, depth) = k;
        let sum = |f: &dyn Fn(&crate::evaluate::clutter::RoundRecord) -> usize| -> usize {
            of.iter().map(|r| f(r)).sum()
        };
        let (tried, held, unsettled) = (
            sum(&|r| r.tried()),
            sum(&|r| r.held()),
            sum(&|r| r.unsettled()),
        );
        let objects = sum(&|r| r.objects) - unsettled;
        let no_grasp = of
            .iter()
            .filter(|r| {
                r.attempts
                    .last()
                    .is_some_and(|a| a.outcome == Outcome::NoGrasp)
            })
            .count();
        let mut phases: BTreeMap<&str, usize> = BTreeMap::new();
        for a in of.iter().flat_map(|r| &r.attempts) {
            if let Outcome::Failed(stage) = &a.outcome {
                *phases.entry(stage.as_str()).or_default() += 1;
            }
        }
        let phases = if phases.is_empty() {
            "-".to_string()
        } else {
            phases
                .iter()
                .map(|(p, n)| format!("{p} {n}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let rate = |k: usize, n: usize| {
            let (lo, hi) = wilson_95(k, n);
            format!(
                "{} ({k} of {n}; {:.0}-{:.0}%)",
                pct(k, n),
                100.0 * lo,
                100.0 * hi
            )
        };
        let _ = writeln!(
            md,
            "| {} | {views} | {cameras} | {depth} | {} | {objects} | {tried} | {} | {} | {no_grasp} | {phases} | {} | {unsettled} |",
            scene.name(),
            of.len(),
            rate(held, tried),
            rate(held, objects),
            sum(&|r| r.fell_out)
        );
    }
    md.push('\n');
}

/// The labels suite's confusion tables: per object group and over all, each label against the
/// outcome.
pub(super) fn labels_table(md: &mut String, results: &Results) {
    use crate::evaluate::labels::Confusion;
    let config = &results.config;
    let records = &results.labels;
    let objects = records
        .iter()
        .map(|r| (&r.set, &r.object))
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    let _ = writeln!(
        md,
        "## Labels\n\nThe labels the networks learn against the trial's outcome: {} antipodal \
         grasps sampled on each of {objects} objects in its most probable resting pose (objects \
         that only roll left out), each labelled by Dex-Net 2.0's robust Ferrari-Canny label, \
         by the physics label (at least half of {} perturbed trials hold) and by both, and \
         judged by an outcome of {} other perturbed trials (held when at least half hold; \
         trials whose object left its pose before the hand came are left out of both; a group \
         with no grasp so judged is not shown). False-positive rate: label positive of the \
         outcomes that failed.\n",
        config.label_grasps, config.label_trials, config.label_outcome_trials
    );
    let _ = writeln!(
        md,
        "| objects | label | grasps | + held | + failed | - held | - failed | agreement | false-positive rate | positives that failed |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    let mut groups: Vec<&str> = records.iter().map(|r| r.group.as_str()).collect();
    groups.sort_unstable();
    groups.dedup();
    groups.push("all");
    for group in groups {
        let tables = Confusion::of(
            records
                .iter()
                .filter(|r| group == "all" || r.group == group),
        );
        if tables[0].0.iter().sum::<usize>() == 0 {
            continue;
        }
        for (Confusion([tp, fp, fn_, tn]), label) in
            tables.iter().zip(["robust", "physics", "both"])
        {
            let n = tp + fp + fn_ + tn;
            let _ = writeln!(
                md,
                "| {group} | {label} | {n} | {tp} | {fp} | {fn_} | {tn} | {} | {} | {} |",
                pct(tp + tn, n),
                pct(*fp, fp + tn),
                pct(*fp, tp + fp)
            );
        }
    }
    let mut failures = mvgrasp_grasp::physics::StageCounts::default();
    for r in records {
        failures += r.outcome_failures;
    }
    let _ = writeln!(
        md,
        "
The outcomes' failed trials: settle {}, approach {}, close {}, lift {}, shake {}.
",
        failures.settle, failures.approach, failures.close, failures.lift, failures.shake
    );
}

/// The speed suite's tables: each policy's stages, and each network in mvgrasp's runtime
/// beside torch.
pub(super) fn speed_tables(md: &mut String, speed: &crate::evaluate::speed::SpeedRecord) {
    let _ = writeln!(
        md,
        "## Speed\n\nEach policy's plan of the default run's object (the built-in mug), the \
         median of {} timed plans after a warm-up, milliseconds, on {} ({} threads). `render`: \
         the views (in colour when the depth comes from RGB); `depth`: predicting their depth \
         from RGB; `fuse`: fusing the views; `plan`: sampling, cropping and scoring candidates, \
         the hand check and re-scoring; `checks`: the analytic label and the physics trial of \
         the best grasp. Timings are measured, not seeded: another run gives other figures.\n",
        speed.runs, speed.cpu, speed.threads
    );
    let _ = writeln!(
        md,
        "| policy | render | depth | fuse | plan | checks | total |\n|---|---|---|---|---|---|---|"
    );
    for s in &speed.stages {
        let _ = writeln!(
            md,
            "| {} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} |",
            s.policy, s.render_ms, s.depth_ms, s.fuse_ms, s.plan_ms, s.check_ms, s.total_ms
        );
    }
    let _ = writeln!(
        md,
        "\nThe shipped GQ-CNNs scoring seeded batches of crops (softmax included) in mvgrasp's \
         runtime and in torch on the same inputs and threads (`benches/gqcnn/bench_torch.py`; \
         `torch-ftz`: with denormals flushed, as mvgrasp's runtime flushes them at load); the \
         mean probability is a check that both scored alike. Peer: {}.\n",
        speed.peer
    );
    let _ = writeln!(
        md,
        "| network | runtime | batch | median (ms) | crops/s | against the faster torch | mean probability |\n|---|---|---|---|---|---|---|"
    );
    for n in &speed.networks {
        // mvgrasp's crops per second over the faster torch's, same network and batch.
        let torch = speed
            .networks
            .iter()
            .filter(|t| t.runtime != "mvgrasp" && (&t.network, t.batch) == (&n.network, n.batch))
            .map(|t| t.crops_per_s)
            .reduce(f64::max);
        let ratio = match torch {
            Some(t) if n.runtime == "mvgrasp" => format!("{:.1}x", n.crops_per_s / t),
            _ => "-".into(),
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.2} | {:.0} | {ratio} | {:.3e} |",
            n.network, n.runtime, n.batch, n.median_ms, n.crops_per_s, n.mean_p
        );
    }
    md.push('\n');
}
