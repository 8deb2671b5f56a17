//! `plan`'s printouts: what a run on a mesh or on a sensor's depth found, in words.

use mvgrasp::infer::Gqcnn;
use mvgrasp::planner::{
    DepthFrom, ObjectSource, PlanReport, SensorFiles, SensorPlanReport, models,
};

/// How a summary names a depth predictor.
pub(crate) fn depth_from_words(from: DepthFrom) -> &'static str {
    match from {
        DepthFrom::Mvs => "the multi-view stereo network (models/mvs_small)",
        DepthFrom::Lsm => "the Learnt Stereo Machine (models/lsm_small)",
        DepthFrom::Baseline => "the plane-sweep baseline",
        DepthFrom::Refined => "the plane sweep refined by its network (models/sweep_refiner_small)",
    }
}

pub(crate) fn sensor_summary(model: &str, files: &SensorFiles, r: &SensorPlanReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let k = &r.view.camera.intrinsics;
    let _ = writeln!(
        s,
        "depth: {} ({} x {}, fx {:.1}, fy {:.1} from {})",
        files.depth.display(),
        k.width,
        k.height,
        k.fx,
        k.fy,
        files.intrinsics.display()
    );
    let t = &r.table;
    let _ = writeln!(
        s,
        "table: fitted in the image, {:.1}% of {} points within 4 mm (rms {:.1} mm); the camera \
         {:.2} m above it, {:.1} deg from level",
        100.0 * t.inlier_share,
        t.points,
        1000.0 * t.rms_residual_m,
        t.camera_height_m,
        r.camera_elevation_deg
    );
    let _ = writeln!(
        s,
        "camera pose: {}",
        match &files.camera_pose {
            Some(path) => format!("from {}", path.display()),
            None => "estimated: the world frame is on the fitted table, z up".into(),
        }
    );
    let _ = writeln!(
        s,
        "object: {} pixels {}",
        r.object_pixels,
        match (r.object, &files.mask) {
            (ObjectSource::MaskFile, Some(path)) => format!("of the mask {}", path.display()),
            _ => "standing on the table (no mask)".into(),
        }
    );
    let _ = writeln!(s, "plan: {model}, {} candidates", r.candidates);
    let rej = &r.rejections;
    let reasons = rej.describe();
    let Some(best) = &r.best else {
        if rej.total() > 0 {
            let _ = writeln!(s, "no grasp: every candidate was rejected: {reasons}");
        } else {
            let _ = writeln!(
                s,
                "no grasp: no antipodal candidate the gripper fits on the object"
            );
        }
        return s;
    };
    if rej.total() > 0 {
        let _ = writeln!(
            s,
            "rejected {} candidates before the best: {reasons}",
            rej.total()
        );
    }
    let g = &best.image;
    let _ = writeln!(
        s,
        "best grasp: quality {:.3}, width {:.1} cm, centre ({:.1}, {:.1}) px at depth {:.3} m, \
         axis {:.1} deg in the image",
        best.quality,
        100.0 * g.width_m,
        g.center_px[0],
        g.center_px[1],
        g.depth_m,
        g.angle_rad.to_degrees()
    );
    let c = r
        .view
        .camera
        .camera_from_world()
        .transform_point(best.grasp.center());
    let p = best.grasp.center();
    let paper = best.grasp.to_paper();
    let _ = writeln!(
        s,
        "  centre in the camera frame ({:+.3}, {:+.3}, {:+.3}) m; in the world ({:+.3}, {:+.3}, \
         {:+.3}) m, phi {:.1} deg, theta {:.1} deg",
        c.x,
        c.y,
        c.z,
        p.x,
        p.y,
        p.z,
        paper.phi_rad.to_degrees(),
        paper.theta_rad.to_degrees()
    );
    let _ = writeln!(
        s,
        "time: read {:.3} s, table {:.3} s, plan {:.3} s",
        r.timings[0], r.timings[1], r.timings[2]
    );
    s
}

/// One line for a plan's best grasp: its quality, robust label and physics verdict.
pub(crate) fn verdict(plan: &PlanReport) -> String {
    let Some(best) = &plan.best else {
        return "no grasp".into();
    };
    let robust = plan
        .analytic
        .as_ref()
        .map_or("", |a| if a.robust { ", robust" } else { ", not robust" });
    let physics = plan
        .physics
        .as_ref()
        .map_or(String::new(), |o| match o.failed_at {
            None => ", held in physics".into(),
            Some(stage) => format!(", failed in physics at {stage:?}"),
        });
    format!("quality {:.3}{robust}{physics}", best.quality)
}

/// The plan on predicted depth beside the same run on the rendered depth.
pub(crate) fn truth_comparison(from: DepthFrom, plan: &PlanReport, truth: &PlanReport) -> String {
    format!(
        "depth: rendered in colour and predicted by {} in {:.2} s of the render time above\n\
         on the rendered (true) depth, the same run: {} (on the predicted depth: {})\n",
        depth_from_words(from),
        plan.timings.depth_s,
        verdict(truth),
        verdict(plan)
    )
}

pub(crate) fn summary(
    model: &str,
    net: &Gqcnn,
    plan: &PlanReport,
    distance_m: f32,
    (fused, planned_in): (bool, Option<usize>),
) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let kind = match (net.architecture().pose_inputs == 2, fused) {
        (multi, false) if planned_in == Some(1) => format!(
            "{} in the first, top-down view; every view predicts the depth",
            if multi { "multi-view GQ-CNN" } else { "GQ-CNN" }
        ),
        (_, true) => format!(
            "the multi-view planner: the views fused, candidates from {}, the best of each view \
             re-scored by {} on virtual views and ranked by their modelled chance to hold \
             (models/ranker_fused.json)",
            if net.architecture().pose_inputs == 2 {
                "the multi-view GQ-CNN"
            } else {
                "the GQ-CNN"
            },
            models::GQCNN_TOPDOWN.name
        ),
        (true, false) => "multi-view GQ-CNN, each view on its own".into(),
        (false, false) => "GQ-CNN".into(),
    };
    let _ = writeln!(
        s,
        "plan: {model} ({kind}), stable pose {} (probability {:.3}), {} view(s) {:.2} m away:",
        plan.stable_pose,
        plan.stable_pose_probability,
        plan.views.len(),
        distance_m
    );
    let _ = writeln!(s, "   view  elevation  candidates  best quality");
    for (i, v) in plan.views.iter().enumerate() {
        let best = v.best_quality.map_or("-".into(), |q| format!("{q:.3}"));
        let _ = writeln!(
            s,
            "   {i:>4}  {:>5.1} deg  {:>10}  {best:>12}",
            v.elevation_deg, v.candidates
        );
    }
    let r = &plan.rejections;
    let Some(best) = &plan.best else {
        let why = if r.total() > 0 {
            format!("every candidate was rejected: {}", r.describe())
        } else {
            "no view had an antipodal candidate the gripper fits".to_string()
        };
        let _ = writeln!(s, "no grasp: {why}");
        return s;
    };
    if r.total() > 0 {
        let _ = writeln!(
            s,
            "rejected {} candidates before the best: {}",
            r.total(),
            r.describe()
        );
    }
    let p = best.grasp.center();
    let _ = writeln!(
        s,
        "best grasp: view {} ({:.0} deg up), quality {:.3}, width {:.1} cm",
        best.view,
        best.theta_rad.to_degrees(),
        best.quality,
        best.grasp.width_m * 100.0
    );
    if let Some(paper) = &plan.best_paper {
        let _ = writeln!(
            s,
            "  g* = (p = ({:+.3}, {:+.3}, {:+.3}) m, phi = {:.1} deg, theta = {:.1} deg)",
            p.x,
            p.y,
            p.z,
            paper.phi_rad.to_degrees(),
            paper.theta_rad.to_degrees()
        );
    }
    if let Some(a) = &plan.analytic {
        let _ = writeln!(
            s,
            "  analytic check: robust epsilon {:.4}, {}, label {}",
            a.robust_epsilon,
            if a.collision_free {
                "collision-free"
            } else {
                "the gripper collides"
            },
            if a.robust { "robust" } else { "not robust" }
        );
    }
    if let Some(o) = &plan.physics {
        let verdict = match o.failed_at {
            None => format!(
                "held (lifted {:.1} cm, slipped {:.1} mm)",
                o.object_lift_m * 100.0,
                o.slip_m * 1000.0
            ),
            Some(stage) => format!("failed at {stage:?}"),
        };
        let _ = writeln!(s, "  physics (rapier: close, lift, shake): {verdict}");
    }
    let _ = writeln!(
        s,
        "time: render {:.2} s, plan {:.2} s, checks {:.2} s",
        plan.timings.render_s, plan.timings.plan_s, plan.timings.check_s
    );
    s
}
