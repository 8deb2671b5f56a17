//! The report folder, written from an evaluation's records alone: `results.json` (every
//! record), `report.md`, the same as a self-contained `report.html`, and `pictures/`.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use base64::Engine as _;

use super::Results;
use super::grasps::{GraspRecord, PlacedObject, PoseKind};
use crate::error::{Error, Result};

/// The colours of the policies' hands in the pictures, in the order of the policies.
pub const POLICY_COLORS: [[u8; 3]; 5] = crate::grasp_image::GRASP_COLORS;

const COLOR_NAMES: [&str; 5] = ["green", "blue", "orange", "purple", "cyan"];

/// The file name of the picture of `placed`'s grasps under `pictures/`.
pub fn picture_name(placed: &PlacedObject) -> String {
    let name: String = format!("{}_{}_pose{}", placed.set, placed.object, placed.pose)
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{name}.png")
}

/// The Wilson score interval of `k` successes in `n` trials at 95% confidence, as fractions
/// (`(0, 1)` for no trials).
pub fn wilson_95(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (k, n, z) = (k as f64, n as f64, 1.959_964);
    let p = k / n;
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// Counts of a set of plans.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Plans whose trial tested the grasp (a missing grasp included; a toppled object not).
    pub trials: usize,
    /// Grasps returned among them.
    pub returned: usize,
    /// Grasps that held.
    pub held: usize,
    /// Plans whose object toppled before the hand came (left out of the rates).
    pub toppled: usize,
    /// Sum of the returned grasps' predicted quality, per mille.
    quality_milli: u64,
}

impl Tally {
    fn add(&mut self, r: &GraspRecord) {
        if !r.counts() {
            self.toppled += 1;
            return;
        }
        self.trials += 1;
        self.returned += usize::from(r.returned());
        self.held += usize::from(r.held());
        self.quality_milli += r.quality.map_or(0, |q| (1e3 * q).round() as u64);
    }

    /// `held of trials (pct%)`.
    pub fn held_cell(&self) -> String {
        if self.trials == 0 {
            return "-".into();
        }
        format!(
            "{} of {} ({:.0}%)",
            self.held,
            self.trials,
            100.0 * self.held as f64 / self.trials as f64
        )
    }

    fn interval(&self) -> String {
        let (lo, hi) = wilson_95(self.held, self.trials);
        format!("{:.0}-{:.0}%", 100.0 * lo, 100.0 * hi)
    }

    fn mean_quality(&self) -> f64 {
        self.quality_milli as f64 / 1e3 / self.returned.max(1) as f64
    }
}

fn pct(k: usize, n: usize) -> String {
    if n == 0 {
        "-".into()
    } else {
        format!("{:.0}%", 100.0 * k as f64 / n as f64)
    }
}

/// Writes `results.json`, `report.md` and `report.html` into `out` (its `pictures/` already
/// drawn).
///
/// # Errors
/// A file that cannot be written.
pub fn write(results: &Results, out: &Path) -> Result<()> {
    let json_path = out.join("results.json");
    let json = serde_json::to_string_pretty(results)
        .map_err(Error::json("write", "results", &json_path))?;
    std::fs::write(&json_path, json + "\n").map_err(Error::io("write", &json_path))?;
    let markdown = markdown(results);
    let md_path = out.join("report.md");
    std::fs::write(&md_path, &markdown).map_err(Error::io("write", &md_path))?;
    let html = html(&markdown, out)?;
    let html_path = out.join("report.html");
    std::fs::write(&html_path, html).map_err(Error::io("write", &html_path))
}

/// The report in Markdown.
pub fn markdown(results: &Results) -> String {
    let mut md = String::new();
    let config = &results.config;
    // Each record's object and pose (object names are unique over the sets).
    let placed: BTreeMap<(&str, usize), &PlacedObject> = results
        .objects
        .iter()
        .map(|p| ((p.object.as_str(), p.pose), p))
        .collect();
    let place = |r: &GraspRecord| placed.get(&(r.object.as_str(), r.pose)).copied();
    let policies: Vec<&str> = results.policies.iter().map(|(n, ..)| n.as_str()).collect();
    let _ = writeln!(md, "# mvgrasp evaluation\n");
    let _ = writeln!(
        md,
        "Object sets: {} ({} built-in per category); seeds {}; {}. {} objects in {} resting \
         poses, {} plans.\n",
        config.sets.join(", "),
        config.per_category,
        config
            .seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", "),
        if config.all_poses {
            "every offered resting pose of at least 5% probability"
        } else {
            "the most probable resting pose"
        },
        results
            .objects
            .iter()
            .map(|p| (&p.set, &p.object))
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        results.objects.len(),
        results.grasps.len()
    );
    if !results.depth.is_empty() {
        depth_tables(&mut md, results);
    }
    if !results.clutter.is_empty() {
        clutter_table(&mut md, results);
    }
    if !results.labels.is_empty() {
        labels_table(&mut md, results);
    }
    if results.grasps.is_empty() {
        return md;
    }
    let _ = writeln!(md, "## Grasps\n");
    let _ = writeln!(
        md,
        "Each policy plans one grasp per object, pose and seed from the views it sees; the \
         project's trial (close, lift, shake) says whether it held. A missing grasp counts as \
         a failure; an object that toppled from its pose before the hand came is left out \
         (the trial tests the pose, not the grasp). Intervals: Wilson, 95%.\n"
    );
    let mut header = String::from(
        "| policy | command | plans on | objects | held (of plans) | 95% interval | grasps returned | precision (held of returned) | toppled |",
    );
    let mut rule = String::from("|---|---|---|---|---|---|---|---|---|");
    let coverage = config.coverage;
    if coverage {
        header.push_str(
            " held where some grasp holds | coverage (returned where some grasp holds) |",
        );
        rule.push_str("---|---|");
    }
    let _ = writeln!(md, "{header}\n{rule}");
    // Each set apart, then all of them together when there are several.
    let mut sets: Vec<&str> = Vec::new();
    for p in &results.objects {
        if !sets.contains(&p.set.as_str()) {
            sets.push(&p.set);
        }
    }
    let mut scopes: Vec<Option<&str>> = sets.iter().copied().map(Some).collect();
    if sets.len() > 1 {
        scopes.push(None);
    }
    for (name, command, about) in &results.policies {
        for scope in &scopes {
            let mut all = Tally::default();
            let mut holdable = Tally::default();
            for r in results.grasps.iter().filter(|r| &r.policy == name) {
                let Some(p) = place(r) else { continue };
                if scope.is_some_and(|s| s != p.set) {
                    continue;
                }
                all.add(r);
                if p.holdable == Some(true) {
                    holdable.add(r);
                }
            }
            let _ = write!(
                md,
                "| {name} | `{command}` | {about} | {} | {} | {} | {} | {} | {} |",
                scope.unwrap_or("all"),
                all.held_cell(),
                all.interval(),
                pct(all.returned, all.trials),
                pct(all.held, all.returned),
                all.toppled
            );
            if coverage {
                let _ = write!(
                    md,
                    " {} | {} |",
                    holdable.held_cell(),
                    pct(holdable.returned, holdable.trials)
                );
            }
            md.push('\n');
        }
    }
    if coverage {
        let holdable = results
            .objects
            .iter()
            .filter(|p| p.holdable == Some(true))
            .count();
        let _ = writeln!(
            md,
            "\nSome grasp in reach holds {holdable} of the {} objects and poses (an exhaustive \
             search on the true mesh: the {} collision-free antipodal grasps of highest robust \
             quality approaching within {} degrees of straight down, tried in the same trial).",
            results.objects.len(),
            super::grasps::SEARCH_TRIALS,
            super::grasps::REACH_TILT_DEG
        );
    }
    calibration_table(&mut md, results);
    // Per category or source, and per pose kind.
    let by = |key: &dyn Fn(&PlacedObject) -> String| {
        let mut table: BTreeMap<String, Vec<Tally>> = BTreeMap::new();
        for r in &results.grasps {
            let Some(p) = place(r) else { continue };
            let Some(column) = policies.iter().position(|n| *n == r.policy) else {
                continue;
            };
            table
                .entry(key(p))
                .or_insert_with(|| vec![Tally::default(); policies.len()])[column]
                .add(r);
        }
        table
    };
    // The policies' columns after `first` leading ones: the header's tail and the rule.
    let columns = |first: &[&str]| {
        let mut names: Vec<&str> = first.to_vec();
        names.extend(&policies);
        format!("| {} |\n|{}", names.join(" | "), "---|".repeat(names.len()))
    };
    let _ = writeln!(md, "\n### Per category or source (held of plans)\n");
    let _ = writeln!(md, "{}", columns(&["category"]));
    for (group, tallies) in by(&|p| p.group.clone()) {
        let cells: Vec<String> = tallies.iter().map(Tally::held_cell).collect();
        let _ = writeln!(md, "| {group} | {} |", cells.join(" | "));
    }
    let _ = writeln!(md, "\n### Per pose kind (held of plans)\n");
    let _ = writeln!(
        md,
        "Upright: taller than its footprint is long; lying: lower; flat and wide: under 0.6 \
         of its footprint's narrow side, which is wider than the hand opens; open at the top: a ray \
         down the footprint's centre falls below a third of the height; thin: under 1.5 cm.\n"
    );
    let _ = writeln!(md, "{}", columns(&["pose kind"]));
    let kinds = by(&|p| format!("{:?}", p.kind));
    for kind in PoseKind::ALL {
        if let Some(tallies) = kinds.get(&format!("{kind:?}")) {
            let cells: Vec<String> = tallies.iter().map(Tally::held_cell).collect();
            let _ = writeln!(md, "| {} | {} |", kind.name(), cells.join(" | "));
        }
    }
    // The seed paper's Table 2: its six categories (its hole punch is the stapler here).
    let groups = by(&|p| p.group.clone());
    let _ = writeln!(
        md,
        "\n### The seed paper's Table 2 layout (predicted quality of the returned grasps, mean / held)\n"
    );
    let _ = writeln!(md, "{}", columns(&["category"]));
    for (paper, ours) in [
        ("bowl", "bowl"),
        ("toy chair", "toy_chair"),
        ("mug", "mug"),
        ("squash", "squash"),
        ("hole punch (stapler)", "stapler"),
        ("toy car", "toy_car"),
    ] {
        if let Some(tallies) = groups.get(ours) {
            let cells: Vec<String> = tallies
                .iter()
                .map(|t| format!("{:.3} / {}", t.mean_quality(), t.held_cell()))
                .collect();
            let _ = writeln!(md, "| {paper} | {} |", cells.join(" | "));
        }
    }
    // Per object.
    let _ = writeln!(md, "\n### Per object (each seed's outcome)\n");
    let mut first = vec!["object", "pose (probability)", "kind"];
    if coverage {
        first.push("some grasp holds");
    }
    let _ = writeln!(md, "{}", columns(&first));
    for p in &results.objects {
        let cells: Vec<String> = policies
            .iter()
            .map(|policy| {
                results
                    .grasps
                    .iter()
                    .filter(|r| r.policy == *policy && r.object == p.object && r.pose == p.pose)
                    .map(|r| r.outcome.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            })
            .collect();
        let holds = match p.holdable {
            Some(true) => " yes |",
            Some(false) => " no |",
            None => "",
        };
        let _ = writeln!(
            md,
            "| {} {} | {} ({:.0}%) | {} |{holds} {} |",
            p.set,
            p.object,
            p.pose,
            100.0 * p.pose_probability,
            p.kind.name(),
            cells.join(" | ")
        );
    }
    if !results.skipped.is_empty() {
        let _ = writeln!(md, "\n### Objects not evaluated\n");
        for (object, why) in &results.skipped {
            let _ = writeln!(md, "- {object}: {why}");
        }
    }
    let _ = writeln!(md, "\n### Pictures (the first seed's grasps)\n");
    let legend: Vec<String> = policies
        .iter()
        .zip(COLOR_NAMES.iter().cycle())
        .map(|(p, c)| format!("{p}: {c}"))
        .collect();
    let _ = writeln!(md, "Hands: {}.\n", legend.join(", "));
    for p in &results.objects {
        let _ = writeln!(
            md,
            "![{} {} pose {}](pictures/{})\n",
            p.set,
            p.object,
            p.pose,
            picture_name(p)
        );
    }
    md
}

/// Upper ends of the calibration table's quality bins.
const QUALITY_BINS: [f32; 6] = [0.5, 0.7, 0.8, 0.9, 0.95, 1.0];

/// Per policy, the returned grasps' predicted quality against how often they held, in bins,
/// and the expected calibration error (the bins' gaps weighted by their grasps).
fn calibration_table(md: &mut String, results: &Results) {
    let _ = writeln!(
        md,
        "\n### Calibration (the returned grasp's predicted quality against held)\n\nPer bin of \
         predicted quality: grasps returned and tried, their mean quality, the share that held. \
         ECE: the expected calibration error, the bins' |mean quality - share held| weighted \
         by their grasps. \"Chance to hold\": the quality mapped to the trial's outcomes on the \
         development set (models/probability_topdown.json for the top-down GQ-CNN, \
         models/probability_fused.json for the multi-view planner's ranker), binned the same \
         way.\n"
    );
    let mut header = String::from("| policy |");
    let mut lower = 0.0;
    for upper in QUALITY_BINS {
        let _ = write!(header, " {lower:.2}-{upper:.2} |");
        lower = upper;
    }
    let _ = writeln!(
        md,
        "{header} ECE |\n|---|{}---|",
        "---|".repeat(QUALITY_BINS.len())
    );
    for (name, ..) in &results.policies {
        let of_policy = || {
            results
                .grasps
                .iter()
                .filter(move |r| &r.policy == name && r.counts())
        };
        calibration_row(
            md,
            name,
            of_policy().filter_map(|r| Some((r.quality?, r.held()))),
        );
        if of_policy().any(|r| r.probability.is_some()) {
            calibration_row(
                md,
                &format!("{name}, chance to hold"),
                of_policy().filter_map(|r| Some((r.probability?, r.held()))),
            );
        }
    }
}

/// One row of the calibration table: `graded` (predicted, held) in [`QUALITY_BINS`], and the
/// expected calibration error.
fn calibration_row(md: &mut String, name: &str, graded: impl Iterator<Item = (f32, bool)>) {
    // (grasps, predicted sum, held) per bin
    let mut bins = [(0usize, 0.0f64, 0usize); QUALITY_BINS.len()];
    for (q, held) in graded {
        let bin = QUALITY_BINS
            .iter()
            .position(|&upper| q < upper)
            .unwrap_or(QUALITY_BINS.len() - 1);
        bins[bin].0 += 1;
        bins[bin].1 += f64::from(q);
        bins[bin].2 += usize::from(held);
    }
    let total: usize = bins.iter().map(|b| b.0).sum();
    let mut ece = 0.0;
    let mut row = format!("| {name} |");
    for &(n, quality, held) in &bins {
        if n == 0 {
            row.push_str(" - |");
            continue;
        }
        let (mean, rate) = (quality / n as f64, held as f64 / n as f64);
        ece += n as f64 / total.max(1) as f64 * (mean - rate).abs();
        let _ = write!(row, " {n}: {mean:.2} / {:.0}% |", 100.0 * rate);
    }
    let _ = writeln!(md, "{row} {:.1} points |", 100.0 * ece);
}

/// The depth suite's tables: per set, the seed paper's Table 1 layout for every method.
fn depth_tables(md: &mut String, results: &Results) {
    use super::depth::{DepthErrors, METHODS};
    let _ = writeln!(
        md,
        "## Depth from RGB\n\nDepth predicted from the first N of the seed paper's 10 test views \
         ({:.2} m away, the first top-down; random colours, masks given) against the rendered \
         depth, over the object's pixels: the median and mean error of the predicted pixels \
         (mm), the share of object pixels predicted, the share within 5 mm (a missing pixel is \
         not within), and the paper's normalised error (mean error over mean true depth). \
         `sweep`: the plane sweep as `plan --rgb` uses it (unconfirmed pixels missing); \
         `sweep-hull`: as the default run plans on it (unconfirmed pixels at the visual hull's \
         depth); `hull`: the visual hull alone; `lsm`, `mvs`: the shipped networks.\n",
        results.config.depth_distance_m
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
        let _ = writeln!(md, "### {set} ({objects} objects)\n");
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
                    format!(
                        "{:.1} | {:.1} | {:.0}% | {:.0}% | {:.4}",
                        e.median_mm(),
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
    }
}

/// The clutter suite's table: per scene and number of views, success and cleared with their
/// intervals, how the rounds ended, and GIGA's published figures beside.
fn clutter_table(md: &mut String, results: &Results) {
    use super::clutter::Outcome;
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
    let key = |r: &super::clutter::RoundRecord| {
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
        let sum = |f: &dyn Fn(&super::clutter::RoundRecord) -> usize| -> usize {
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
fn labels_table(md: &mut String, results: &Results) {
    use super::labels::Confusion;
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

/// `markdown` (the subset [`markdown`] writes: headings, paragraphs, lists, tables, images,
/// inline code) as one HTML page, its pictures from `out` inlined.
fn html(markdown: &str, out: &Path) -> Result<String> {
    let mut html = String::from(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>mvgrasp evaluation</title>\n\
         <style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}\
         table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:3px 8px;\
         font-size:90%}img{max-width:32%;margin:2px}code{background:#f3f3f3}</style>\n</head><body>\n",
    );
    let mut in_table = false;
    let mut in_list = false;
    for line in markdown.lines() {
        let is_row = line.starts_with('|');
        if in_table && !is_row {
            html.push_str("</table>\n");
            in_table = false;
        }
        let is_item = line.starts_with("- ");
        if in_list && !is_item {
            html.push_str("</ul>\n");
            in_list = false;
        }
        if is_row {
            let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
            if cells.iter().all(|c| c.chars().all(|ch| ch == '-')) {
                continue;
            }
            let tag = if in_table { "td" } else { "th" };
            if !in_table {
                html.push_str("<table>\n");
                in_table = true;
            }
            html.push_str("<tr>");
            for cell in cells {
                let _ = write!(html, "<{tag}>{}</{tag}>", inline(cell));
            }
            html.push_str("</tr>\n");
        } else if let Some(item) = line.strip_prefix("- ") {
            if !in_list {
                html.push_str("<ul>\n");
                in_list = true;
            }
            let _ = writeln!(html, "<li>{}</li>", inline(item));
        } else if let Some(rest) = line.strip_prefix("![") {
            let (alt, rest) = rest.split_once("](").unwrap_or((rest, ""));
            let file = rest.trim_end_matches(')');
            let path = out.join(file);
            match std::fs::read(&path) {
                Ok(bytes) => {
                    let data = base64::engine::general_purpose::STANDARD.encode(bytes);
                    let _ = writeln!(
                        html,
                        "<img alt=\"{}\" title=\"{}\" src=\"data:image/png;base64,{data}\">",
                        escape(alt),
                        escape(alt)
                    );
                }
                Err(_) => {
                    let _ = writeln!(html, "<p>(missing picture {})</p>", escape(file));
                }
            }
        } else if let Some(level) =
            (1..=3).find(|&l| line.starts_with(&format!("{} ", "#".repeat(l))))
        {
            let _ = writeln!(html, "<h{level}>{}</h{level}>", inline(&line[level + 1..]));
        } else if !line.is_empty() {
            let _ = writeln!(html, "<p>{}</p>", inline(line));
        }
    }
    if in_table {
        html.push_str("</table>\n");
    }
    if in_list {
        html.push_str("</ul>\n");
    }
    html.push_str("</body></html>\n");
    Ok(html)
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Inline Markdown: `code` spans.
fn inline(text: &str) -> String {
    let escaped = escape(text);
    let mut out = String::new();
    for (i, part) in escaped.split('`').enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<code>{part}</code>");
        } else {
            out.push_str(part);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_intervals_hold_the_rate_and_narrow_with_trials() {
        let (lo, hi) = wilson_95(8, 10);
        assert!(lo < 0.8 && 0.8 < hi);
        let (lo2, hi2) = wilson_95(80, 100);
        assert!(hi2 - lo2 < hi - lo);
        assert_eq!(wilson_95(0, 0), (0.0, 1.0));
    }

    #[test]
    fn the_html_has_every_table_row_and_escapes_text() {
        let md = "# T\n\n| a | b |\n|---|---|\n| <x> | `y` |\n\n- one\n";
        let html = html(md, Path::new("/nonexistent")).unwrap();
        assert!(html.contains("<th>a</th><th>b</th>"), "{html}");
        assert!(
            html.contains("<td>&lt;x&gt;</td><td><code>y</code></td>"),
            "{html}"
        );
        assert!(html.contains("<li>one</li>"));
    }
}
