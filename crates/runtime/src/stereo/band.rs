//! One band of a reference view's rows swept through every depth plane.
//!
//! Per plane: the other views' masks carve the band's points ([`Target::near_object`]), each
//! other view correlates its colours at the points left with the reference's ([`window`]), and
//! a point's cost is the mean of its `best_views` smallest (as [`super::sweep_depths`]
//! describes). Each pixel keeps its cheapest plane with its neighbours' costs, and the first
//! plane that carving leaves it.
//!
//! The windows reach `r` rows beyond the band, so a band computes those rows of its neighbours
//! again: bands are independent, and a pixel's sums are the same bits whatever the bands. The
//! loops run over whole rows of plain arrays without branches where they can, so that the
//! compiler vectorises them; a point that a view does not see samples its
//! [`Target::nowhere`], which is black and carves nothing.
//!
//! [`window`]: super::window

use std::ops::Range;

use super::RULED_OUT;
use super::project::{Located, Target};
use super::sweep::ViewSweep;
use super::window::{correlation_cost, moments, sum_across, sum_down};

/// A plane index for "none".
pub(super) const NO_PLANE: u32 = u32::MAX;

/// A pixel's cheapest plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Best {
    /// Its cost.
    pub cost: f32,
    /// Its index ([`NO_PLANE`] if none).
    pub plane: u32,
    /// The cost of the plane before it ([`RULED_OUT`] for the first).
    pub before: f32,
    /// The cost of the plane after it ([`RULED_OUT`] for the last).
    pub after: f32,
}

/// What a band's sweep leaves per pixel, row-major over its rows and the box's columns.
#[derive(Debug, PartialEq)]
pub(super) struct BandResult {
    /// The band's rows of the box.
    pub rows: Range<usize>,
    /// The cheapest plane.
    pub best: Vec<Best>,
    /// The first plane that carving leaves ([`NO_PLANE`] if none).
    pub hull: Vec<u32>,
}

/// Sweeps rows `rows` of `view`'s box through its planes.
pub(super) fn sweep_band(view: &ViewSweep<'_>, rows: Range<usize>) -> BandResult {
    let mut band = Band::new(view, rows.clone());
    let (n, cols) = (band.centre_len(), band.cols);
    let mut cheapest = Cheapest::new(n);
    // Planes p - 2, p - 1 and p (all ruled out before the first).
    let mut planes: [PlaneCosts; 3] = std::array::from_fn(|_| PlaneCosts::new(n));
    for p in 0..=view.planes.len() {
        planes.rotate_left(1);
        let next = &mut planes[2];
        next.clear(cols);
        if let Some(&depth) = view.planes.get(p) {
            next.span = band.plane_costs(depth, &mut next.costs);
            cheapest.mark_hull(next, p as u32, cols);
        }
        // Plane p - 1 is now complete with both neighbours.
        if p > 0 {
            cheapest.update(&planes, (p - 1) as u32, cols);
        }
    }
    band.to_box_columns(rows, &cheapest)
}

/// One plane's costs over a band's centre pixels, [`RULED_OUT`] outside the columns `span`.
struct PlaneCosts {
    costs: Vec<f32>,
    span: Range<usize>,
}

impl PlaneCosts {
    fn new(n: usize) -> Self {
        Self {
            costs: vec![RULED_OUT; n],
            span: 0..0,
        }
    }

    /// Rules every pixel out again (rows `cols` wide).
    fn clear(&mut self, cols: usize) {
        for row in self.costs.chunks_exact_mut(cols) {
            row[self.span.clone()].fill(RULED_OUT);
        }
        self.span = 0..0;
    }
}

/// Per centre pixel (structure of arrays): the cheapest plane so far ([`Best`]'s fields), and
/// the first plane that carving leaves.
struct Cheapest {
    cost: Vec<f32>,
    plane: Vec<u32>,
    before: Vec<f32>,
    after: Vec<f32>,
    hull: Vec<u32>,
}

impl Cheapest {
    fn new(n: usize) -> Self {
        Self {
            cost: vec![RULED_OUT; n],
            plane: vec![NO_PLANE; n],
            before: vec![RULED_OUT; n],
            after: vec![RULED_OUT; n],
            hull: vec![NO_PLANE; n],
        }
    }

    /// Marks plane `p` as the hull's where it is the first with a finite cost.
    fn mark_hull(&mut self, plane: &PlaneCosts, p: u32, cols: usize) {
        let rows = plane
            .costs
            .chunks_exact(cols)
            .zip(self.hull.chunks_exact_mut(cols));
        for (costs, hull) in rows {
            let span = plane.span.clone();
            for (h, c) in hull[span.clone()].iter_mut().zip(&costs[span]) {
                if c.is_finite() && *h == NO_PLANE {
                    *h = p;
                }
            }
        }
    }

    /// Takes plane `p` (the middle of `planes`: before, at, after) where it is cheaper than the
    /// cheapest so far (the first of equal costs stays).
    fn update(&mut self, [before, at, after]: &[PlaneCosts; 3], p: u32, cols: usize) {
        let span = at.span.clone();
        for row in 0..self.cost.len() / cols {
            let r = row * cols + span.start..row * cols + span.end;
            let (cost, plane) = (&mut self.cost[r.clone()], &mut self.plane[r.clone()]);
            let (b, a) = (&mut self.before[r.clone()], &mut self.after[r.clone()]);
            let (costs, left, right) = (
                &at.costs[r.clone()],
                &before.costs[r.clone()],
                &after.costs[r],
            );
            for i in 0..costs.len() {
                let cheaper = costs[i] < cost[i];
                cost[i] = if cheaper { costs[i] } else { cost[i] };
                plane[i] = if cheaper { p } else { plane[i] };
                b[i] = if cheaper { left[i] } else { b[i] };
                a[i] = if cheaper { right[i] } else { a[i] };
            }
        }
    }
}

/// A band's pixels and scratch. Its layout: the band's rows with `r` rows of margin above and
/// below, each `r` columns wider than the box on either side ([`super::window`]); the centre
/// arrays hold the band's own rows, as wide.
struct Band<'v, 'a> {
    view: &'v ViewSweep<'a>,
    /// The first box row of the layout (`r` above the band's), possibly negative.
    top: isize,
    /// The layout's width.
    cols: usize,
    /// The layout's rows that lie in the box.
    inside: Range<usize>,
    /// Per row: the columns from its first object pixel to its last.
    object_columns: Vec<Range<usize>>,
    /// Per pixel: the reference's object (false beyond the box).
    object: Vec<bool>,
    /// Per pixel: the reference's colour (zero off the object).
    own: [Vec<f32>; 3],
    /// Per pixel: the reference's channels' sum and their squares' sum (zero off the object).
    own_terms: [Vec<f32>; 2],
    /// Per target: where this plane's points land (out of sight where carved).
    located: Vec<Located>,
    /// Per target: whether it sees every point left on this plane.
    sees_all: Vec<bool>,
    /// Per pixel: its point on this plane is the object's and no mask carves it away.
    on_hull: Vec<bool>,
    /// Per row: the columns from its first point on the hull to its last.
    hull_columns: Vec<Range<usize>>,
    /// Per row: the columns whose horizontal sums the centre rows' windows need (those of the
    /// centre rows within `r`).
    summed: Vec<Range<usize>>,
    /// Per row: the indices of the pixels whose terms those sums need (`summed` grown by `r`).
    terms_rows: Vec<Range<usize>>,
    /// The columns of the centre rows' points on the hull.
    span: Range<usize>,
    /// Scratch for a row: three terms, a target's colours, and three window sums.
    row_terms: [Vec<f32>; 3],
    row_colours: Vec<[f32; 4]>,
    row_sums: [Vec<f32>; 3],
    /// Per pixel, the horizontal sums of the reference's terms (count, a, a^2) and of a
    /// target's (b, b^2, ab).
    own_across: [Vec<f32>; 3],
    their_across: [Vec<f32>; 3],
    /// Per centre pixel, the reference's window over the points on the hull (those of every
    /// target that sees all of them): its count, and its mean and variance ([`moments`]).
    shared: [Vec<f32>; 3],
    /// The same over the points a target sees when it misses some.
    partial: [Vec<f32>; 3],
    /// Per target, the centre pixels' costs (NaN where it does not see the point).
    costs: Vec<Vec<f32>>,
    /// Per centre pixel: its `best_views` smallest costs, ascending, the number of targets
    /// that see it, and a scratch cost.
    smallest: Vec<Vec<f32>>,
    seen: Vec<u32>,
    carry: Vec<f32>,
}

impl<'v, 'a> Band<'v, 'a> {
    fn new(view: &'v ViewSweep<'a>, rows: Range<usize>) -> Self {
        let r = view.radius;
        let area = &view.area;
        let (cols, height) = (area.w + 2 * r, rows.len() + 2 * r);
        let top = rows.start as isize - r as isize;
        let first = (-top).max(0) as usize;
        let inside = first..(area.h as isize - top).clamp(0, height as isize) as usize;
        let reference = view.reference;
        let image_w = reference.camera.intrinsics.width as usize;
        let mut object = vec![false; cols * height];
        let mut own: [Vec<f32>; 3] = std::array::from_fn(|_| vec![0.0; cols * height]);
        let mut own_terms: [Vec<f32>; 2] = std::array::from_fn(|_| vec![0.0; cols * height]);
        for row in inside.clone() {
            let y = (top + row as isize) as usize;
            for x in 0..area.w {
                let image = (y + area.v0) * image_w + x + area.u0;
                if !reference.mask.as_ref().is_none_or(|m| m[image]) {
                    continue;
                }
                let j = row * cols + x + r;
                object[j] = true;
                let a = reference.rgb[image].map(f32::from);
                for (o, a) in own.iter_mut().zip(a) {
                    o[j] = a;
                }
                // Summed as the channels come, from zero.
                own_terms[0][j] = a[0] + a[1] + a[2];
                own_terms[1][j] = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
            }
        }
        let centre = cols * rows.len();
        let targets = view.targets.len();
        let object_columns = object
            .chunks_exact(cols)
            .map(|line| first_to_last(line).unwrap_or(0..0))
            .collect();
        Self {
            view,
            top,
            cols,
            inside,
            object_columns,
            object,
            own,
            own_terms,
            located: view
                .targets
                .iter()
                .map(|target| Located::with_len(cols * height, target))
                .collect(),
            sees_all: vec![true; targets],
            on_hull: vec![false; cols * height],
            hull_columns: vec![0..0; height],
            summed: vec![0..0; height],
            terms_rows: vec![0..0; height],
            span: 0..0,
            row_terms: std::array::from_fn(|_| vec![0.0; cols]),
            row_colours: vec![[0.0; 4]; cols],
            row_sums: std::array::from_fn(|_| vec![0.0; cols]),
            own_across: std::array::from_fn(|_| vec![0.0; cols * height]),
            their_across: std::array::from_fn(|_| vec![0.0; cols * height]),
            shared: std::array::from_fn(|_| vec![0.0; centre]),
            partial: std::array::from_fn(|_| vec![0.0; centre]),
            costs: vec![vec![f32::NAN; centre]; targets],
            smallest: vec![vec![f32::INFINITY; centre]; view.best_views],
            seen: vec![0; centre],
            carry: vec![0.0; centre],
        }
    }

    /// The number of centre pixels (the band's rows, the layout's width).
    fn centre_len(&self) -> usize {
        self.shared[0].len()
    }

    /// The indices of row `row`'s columns `columns`.
    fn at(&self, row: usize, columns: &Range<usize>) -> Range<usize> {
        row * self.cols + columns.start..row * self.cols + columns.end
    }

    /// The centre pixels' costs on the plane at depth `d` into `raw`, which holds
    /// [`RULED_OUT`] ([`RULED_OUT`] where a mask carves the point away or no target sees it);
    /// the columns where some may be finite.
    ///
    /// Row by row, a target's terms are made and summed across (the row's buffers stay in the
    /// cache), then its windows are summed down and correlated, again row by row; the
    /// reference's window sums over the points on the hull serve every target that sees them
    /// all.
    fn plane_costs(&mut self, d: f32, raw: &mut [f32]) -> Range<usize> {
        if !self.carve(d) {
            return 0..0;
        }
        self.forget_carved();
        self.own_sums(None);
        for t in 0..self.view.targets.len() {
            if !self.sees_all[t] {
                self.own_sums(Some(t));
            }
            self.their_sums_across(t);
            self.target_costs(t);
        }
        self.combine(raw);
        self.span.clone()
    }

    /// The reference's windows at the centre pixels (count, mean, variance), over the points on
    /// the hull into `shared`, or with `target`, over those it sees into `partial`.
    fn own_sums(&mut self, target: Option<usize>) {
        let (cols, r) = (self.cols, self.view.radius);
        for (row, range) in self.terms_rows.iter().cloned().enumerate() {
            if range.is_empty() {
                continue;
            }
            let summed = self.at(row, &self.summed[row]);
            let mut terms = self.row_terms.each_mut().map(|t| &mut t[..range.len()]);
            match target {
                None => {
                    let known = self.on_hull[range.clone()].iter().copied();
                    own_terms(known, &self.own_terms, &mut terms, range);
                }
                Some(t) => {
                    let nowhere = self.view.targets[t].nowhere();
                    let at = &self.located[t].at[range.clone()];
                    let known = at.iter().map(|&at| at != nowhere);
                    own_terms(known, &self.own_terms, &mut terms, range);
                }
            }
            for (terms, across) in terms.iter().zip(&mut self.own_across) {
                sum_across(terms, &mut across[summed.clone()], r);
            }
        }
        let sums = if target.is_some() {
            &mut self.partial
        } else {
            &mut self.shared
        };
        let height = self.summed.len();
        for (cy, span) in self.hull_columns[r..height - r].iter().enumerate() {
            let centre = cy * cols + span.start..cy * cols + span.end;
            let [n, mean, variance] = sums.each_mut().map(|s| &mut s[centre.clone()]);
            sum_down(&self.own_across[0], (cols, cy, span.clone()), n, r);
            sum_down(&self.own_across[1], (cols, cy, span.clone()), mean, r);
            sum_down(&self.own_across[2], (cols, cy, span.clone()), variance, r);
            for i in 0..n.len() {
                [mean[i], variance[i]] = moments(n[i], mean[i], variance[i]);
            }
        }
    }

    /// Target `t`'s terms (b, b^2, ab) summed across into `their_across`.
    fn their_sums_across(&mut self, t: usize) {
        let r = self.view.radius;
        let (target, located) = (self.view.targets[t], &self.located[t]);
        for (row, range) in self.terms_rows.iter().cloned().enumerate() {
            if range.is_empty() {
                continue;
            }
            let summed = self.at(row, &self.summed[row]);
            let mut terms = self.row_terms.each_mut().map(|t| &mut t[..range.len()]);
            let colours = &mut self.row_colours[..range.len()];
            their_terms((target, located), &self.own, (&mut terms, colours), range);
            for (terms, across) in terms.iter().zip(&mut self.their_across) {
                sum_across(terms, &mut across[summed.clone()], r);
            }
        }
    }

    /// Target `t`'s costs at the centre pixels (NaN where it does not see the point): its
    /// windows summed down and correlated with the reference's.
    fn target_costs(&mut self, t: usize) {
        let (cols, r) = (self.cols, self.view.radius);
        let nowhere = self.view.targets[t].nowhere();
        let own = if self.sees_all[t] {
            &self.shared
        } else {
            &self.partial
        };
        let height = self.summed.len();
        for (cy, span) in self.hull_columns[r..height - r].iter().enumerate() {
            let centre = cy * cols + span.start..cy * cols + span.end;
            let mut theirs = self.row_sums.each_mut().map(|s| &mut s[..span.len()]);
            for (across, sums) in self.their_across.iter().zip(theirs.iter_mut()) {
                sum_down(across, (cols, cy, span.clone()), sums, r);
            }
            let at = &self.located[t].at[centre.start + r * cols..centre.end + r * cols];
            let [n, mean, variance] = own.each_ref().map(|s| &s[centre.clone()]);
            let [sb, sbb, sab] = theirs.each_ref().map(|s| &s[..]);
            let costs = &mut self.costs[t][centre];
            for i in 0..costs.len() {
                let own = [mean[i], variance[i]];
                let cost = correlation_cost(n[i], own, [sb[i], sbb[i], sab[i]]);
                costs[i] = if at[i] != nowhere { cost } else { f32::NAN };
            }
        }
    }

    /// Carves the band's points on the plane at depth `d` by the targets' masks, locating them
    /// on the way, and finds the columns of the points left; whether any centre point is left.
    fn carve(&mut self, d: f32) -> bool {
        let (cols, r) = (self.cols, self.view.radius);
        for row in self.inside.clone() {
            let range = self.at(row, &self.object_columns[row]);
            self.on_hull[range.clone()].copy_from_slice(&self.object[range]);
            self.hull_columns[row] = self.object_columns[row].clone();
        }
        let area = &self.view.area;
        for (&target, located) in self.view.targets.iter().zip(&mut self.located) {
            for row in self.inside.clone() {
                let points = self.hull_columns[row].clone();
                if points.is_empty() {
                    continue;
                }
                let y = (self.top + row as isize) as usize;
                let first = y * area.w + points.start - r;
                let range = row * cols + points.start..row * cols + points.end;
                let (at, fu, fv) = (
                    &mut located.at[range.clone()],
                    &mut located.fu[range.clone()],
                    &mut located.fv[range.clone()],
                );
                let pixels = first..first + at.len();
                self.view.rays.locate(target, d, pixels, (&mut *at, fu, fv));
                if target.has_mask() {
                    let line = &mut self.on_hull[range];
                    for (h, &at) in line.iter_mut().zip(&*at) {
                        *h &= target.near_object(at);
                    }
                    // The points left lie within those before.
                    self.hull_columns[row] = first_to_last(line).map_or(0..0, |left| {
                        points.start + left.start..points.start + left.end
                    });
                }
            }
        }
        let height = self.hull_columns.len();
        let centre = &self.hull_columns[r..height - r];
        self.span = centre.iter().cloned().reduce(union).unwrap_or(0..0);
        let rows = self.summed.iter_mut().zip(&mut self.terms_rows).enumerate();
        for (row, (summed, terms)) in rows {
            let near = row.saturating_sub(r).max(r)..(row + r + 1).min(height - r);
            let columns = near
                .map(|y| self.hull_columns[y].clone())
                .reduce(union)
                .unwrap_or(0..0);
            *terms = if columns.is_empty() {
                0..0
            } else {
                row * cols + columns.start - r..row * cols + columns.end + r
            };
            *summed = columns;
        }
        !self.span.is_empty()
    }

    /// Moves the carved points out of every target's sight where the windows need their
    /// terms, and notes which targets see every point left there.
    fn forget_carved(&mut self) {
        for (t, located) in self.located.iter_mut().enumerate() {
            let nowhere = self.view.targets[t].nowhere();
            let mut missing = false;
            for range in self.terms_rows.iter().cloned() {
                let on_hull = &self.on_hull[range.clone()];
                for (at, &h) in located.at[range].iter_mut().zip(on_hull) {
                    *at = if h { *at } else { nowhere };
                    missing |= h & (*at == nowhere);
                }
            }
            self.sees_all[t] = !missing;
        }
    }

    /// Each centre point's cost from its targets' into `raw` (where on the hull): the mean of
    /// the `best_views` smallest finite ones ([`RULED_OUT`] if none), summed in ascending order.
    fn combine(&mut self, raw: &mut [f32]) {
        let (cols, r) = (self.cols, self.view.radius);
        let height = self.hull_columns.len();
        for (cy, span) in self.hull_columns[r..height - r].iter().enumerate() {
            let centre = cy * cols + span.start..cy * cols + span.end;
            let (seen, carry) = (
                &mut self.seen[centre.clone()],
                &mut self.carry[centre.clone()],
            );
            seen.fill(0);
            for smallest in &mut self.smallest {
                smallest[centre.clone()].fill(f32::INFINITY);
            }
            for costs in &self.costs {
                for ((carry, seen), &cost) in
                    carry.iter_mut().zip(&mut *seen).zip(&costs[centre.clone()])
                {
                    let finite = cost.is_finite();
                    *seen += u32::from(finite);
                    *carry = if finite { cost } else { f32::INFINITY };
                }
                // Insertion by exchange: each kept value keeps the smaller of itself and the
                // carried one, and passes the larger on.
                for smallest in &mut self.smallest {
                    for (kept, carry) in smallest[centre.clone()].iter_mut().zip(&mut *carry) {
                        let smaller = *carry < *kept;
                        (*kept, *carry) = if smaller {
                            (*carry, *kept)
                        } else {
                            (*kept, *carry)
                        };
                    }
                }
            }
            let raw = &mut raw[centre.clone()];
            carry.fill(0.0);
            let best_views = self.smallest.len() as u32;
            for (k, smallest) in self.smallest.iter().enumerate() {
                let smallest = &smallest[centre.clone()];
                for i in 0..raw.len() {
                    carry[i] += if (k as u32) < seen[i] {
                        smallest[i]
                    } else {
                        0.0
                    };
                }
            }
            for i in 0..raw.len() {
                let k = seen[i].min(best_views);
                raw[i] = if k > 0 {
                    carry[i] / k as f32
                } else {
                    RULED_OUT
                };
            }
        }
    }

    /// The band's results over the box's columns.
    fn to_box_columns(&self, rows: Range<usize>, cheapest: &Cheapest) -> BandResult {
        let (cols, r, w) = (self.cols, self.view.radius, self.view.area.w);
        let best: Vec<Best> = (0..cheapest.cost.len())
            .map(|i| Best {
                cost: cheapest.cost[i],
                plane: cheapest.plane[i],
                before: cheapest.before[i],
                after: cheapest.after[i],
            })
            .collect();
        BandResult {
            rows,
            best: box_columns(&best, cols, r..r + w),
            hull: box_columns(&cheapest.hull, cols, r..r + w),
        }
    }
}

/// The positions from the first `true` of `line` to its last, if any.
fn first_to_last(line: &[bool]) -> Option<Range<usize>> {
    let first = line.iter().position(|&b| b)?;
    let last = line.iter().rposition(|&b| b)?;
    Some(first..last + 1)
}

/// The smallest range holding both `a` and `b` (either of them if the other is empty).
fn union(a: Range<usize>, b: Range<usize>) -> Range<usize> {
    match (a.is_empty(), b.is_empty()) {
        (true, _) => b,
        (_, true) => a,
        _ => a.start.min(b.start)..a.end.max(b.end),
    }
}

/// Columns `columns` of every row of `values` (rows `cols` wide), row-major.
fn box_columns<T: Copy>(values: &[T], cols: usize, columns: Range<usize>) -> Vec<T> {
    values
        .chunks_exact(cols)
        .flat_map(|row| &row[columns.clone()])
        .copied()
        .collect()
}

/// The reference's terms (count, a, a^2) of the pixels `range` (layout indices) into
/// `terms`: those of the reference's `own_terms` where `known`, zero elsewhere.
fn own_terms(
    known: impl Iterator<Item = bool>,
    own_terms: &[Vec<f32>; 2],
    [count, sum, squares]: &mut [&mut [f32]; 3],
    range: Range<usize>,
) {
    let (own_sum, own_squares) = (&own_terms[0][range.clone()], &own_terms[1][range]);
    for (i, known) in known.enumerate().take(count.len()) {
        count[i] = if known { 3.0 } else { 0.0 };
        sum[i] = if known { own_sum[i] } else { 0.0 };
        squares[i] = if known { own_squares[i] } else { 0.0 };
    }
}

/// A target's terms (b, b^2, ab; the channels summed as they come) of the pixels `range`
/// (layout indices) into `terms`: zero where it does not see the point (its sample is black).
/// `colours`: scratch, for its colours there.
fn their_terms(
    (target, located): (&Target, &Located),
    own: &[Vec<f32>; 3],
    ([sum, squares, products], colours): (&mut [&mut [f32]; 3], &mut [[f32; 4]]),
    range: Range<usize>,
) {
    let (at, fu, fv) = (
        &located.at[range.clone()],
        &located.fu[range.clone()],
        &located.fv[range.clone()],
    );
    let nowhere = target.nowhere();
    for i in 0..colours.len() {
        // Black out of sight; the branch skips the look-ups (and is taken in runs).
        colours[i] = if at[i] == nowhere {
            [0.0; 4]
        } else {
            target.colour(at[i], (fu[i], fv[i]))
        };
    }
    let [a0, a1, a2] = own.each_ref().map(|o| &o[range.clone()]);
    for i in 0..sum.len() {
        let (a, b) = ([a0[i], a1[i], a2[i]], colours[i]);
        sum[i] = b[0] + b[1] + b[2];
        squares[i] = b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
        products[i] = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    }
}
