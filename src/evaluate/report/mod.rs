//! The report folder, written from an evaluation's records alone: `results.json` (every
//! record), `report.md`, the same as a self-contained `report.html`, and `pictures/`.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::Results;
use super::grasps::{GraspRecord, PlacedObject, PoseKind};
use crate::error::{Error, Result};
use html::html;
use suites::{clutter_table, depth_tables, labels_table, speed_tables};

mod html;
mod suites;

/// The colours of the policies' hands in the pictures, in the order of the policies.
pub const POLICY_COLORS: [[u8; 3]; 5] = crate::grasp_image::GRASP_COLORS;

const COLOR_NAMES: [&str; 5] = ["green", "blue", "orange", "purple", "cyan"];

/// The file name of the picture of `placed`'s grasps under `pictures/`.
pub fn picture_name(placed: &PlacedObject) -> String {
    png_name(&format!(
        "{}_{}_pose{}",
        placed.set, placed.object, placed.pose
    ))
}

/// `text` as a PNG's file name: every character but ASCII letters, digits, `-` and `_` made
/// `_`.
pub fn png_name(text: &str) -> String {
    let name: String = text
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
    if let Some(speed) = &results.speed {
        speed_tables(&mut md, speed);
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
}
