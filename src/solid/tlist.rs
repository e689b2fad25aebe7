//! Ray casting of CSG trees by t-lists (§10.7–10.8).
//!
//! Along a ray `q(t) = o + t d` every solid is a sorted list of disjoint intervals
//! `[t_in, t_out]` where the ray is inside. Leaves give their list exactly (sphere §10.6.1,
//! box, cylinder, plane) or by root finding (§10.6.2: sampling `F` then bisection; cone,
//! torus, blends). Interior nodes combine their children's lists: union merges,
//! intersection keeps overlaps, difference removes. Intersection and difference stop as soon
//! as the running list is empty and only look for later children inside its hull.
//! The volume of a solid is `Σ (length of the t-list) · (area per ray)` over a grid of
//! parallel rays (§10.8).

use super::field::Node;
use crate::mesh::vec3::{cross, dot, norm, scale, sub};
use crate::{Error, Result};
use rayon::prelude::*;

type V3 = [f64; 3];

/// A sorted list of disjoint closed intervals of the ray parameter.
pub type TList = Vec<(f64, f64)>;

/// Samples per ray segment used by root finding for non-analytic leaves.
pub const DEFAULT_STEPS: usize = 96;

/// Union of two t-lists.
pub fn union(a: &[(f64, f64)], b: &[(f64, f64)]) -> TList {
    let mut all: Vec<(f64, f64)> = a.iter().chain(b.iter()).copied().collect();
    all.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut out: TList = Vec::with_capacity(all.len());
    for iv in all {
        match out.last_mut() {
            Some(last) if iv.0 <= last.1 => last.1 = last.1.max(iv.1),
            _ => out.push(iv),
        }
    }
    out
}

/// Intersection of two t-lists.
pub fn intersection(a: &[(f64, f64)], b: &[(f64, f64)]) -> TList {
    let (mut i, mut j) = (0, 0);
    let mut out = Vec::new();
    while i < a.len() && j < b.len() {
        let lo = a[i].0.max(b[j].0);
        let hi = a[i].1.min(b[j].1);
        if lo < hi {
            out.push((lo, hi));
        }
        if a[i].1 < b[j].1 {
            i += 1;
        } else {
            j += 1;
        }
    }
    out
}

/// `a` minus `b`.
pub fn difference(a: &[(f64, f64)], b: &[(f64, f64)]) -> TList {
    let mut out = Vec::new();
    let mut j = 0;
    for &(mut lo, hi) in a {
        while j < b.len() && b[j].1 <= lo {
            j += 1;
        }
        let mut k = j;
        while k < b.len() && b[k].0 < hi {
            if b[k].0 > lo {
                out.push((lo, b[k].0));
            }
            lo = lo.max(b[k].1);
            k += 1;
        }
        if lo < hi {
            out.push((lo, hi));
        }
    }
    out
}

/// Total length of a t-list.
pub fn length(t: &[(f64, f64)]) -> f64 {
    t.iter().map(|(a, b)| b - a).sum()
}

/// Roots `s₁ ≤ s₂` of `|f + s u|² = r²` for unit `u`, computed without cancellation:
/// `h² = (r − |f⊥|)(r + |f⊥|)`, the far root from `−b ∓ h`, the near one from `s₁ s₂ = |f|² − r²`.
fn unit_quadratic(f: V3, u: V3, r: f64) -> Option<(f64, f64)> {
    let b = dot(f, u);
    let perp = norm(sub(f, scale(u, b)));
    let h2 = (r - perp) * (r + perp);
    if h2 < 0.0 {
        return None;
    }
    let h = h2.sqrt();
    let fl = norm(f);
    let c = (fl - r) * (fl + r);
    let (s1, s2) = if b > 0.0 {
        let s1 = -b - h;
        (s1, if s1 != 0.0 { c / s1 } else { 0.0 })
    } else {
        let s2 = -b + h;
        (if s2 != 0.0 { c / s2 } else { 0.0 }, s2)
    };
    Some((s1.min(s2), s1.max(s2)))
}

/// Exact ray–sphere interval (§10.6.1): the `t` with `|o + t d − c| ≤ r`.
pub fn ray_sphere(o: V3, d: V3, c: V3, r: f64) -> Option<(f64, f64)> {
    let l = norm(d);
    if l == 0.0 {
        return None;
    }
    let u = scale(d, 1.0 / l);
    unit_quadratic(sub(o, c), u, r).map(|(a, b)| (a / l, b / l))
}

/// Ray–box interval by slabs.
fn ray_box(o: V3, d: V3, lo: V3, hi: V3) -> Option<(f64, f64)> {
    let mut t0 = f64::NEG_INFINITY;
    let mut t1 = f64::INFINITY;
    for i in 0..3 {
        if d[i] == 0.0 {
            if o[i] < lo[i] || o[i] > hi[i] {
                return None;
            }
        } else {
            let a = (lo[i] - o[i]) / d[i];
            let b = (hi[i] - o[i]) / d[i];
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
    }
    (t0 < t1).then_some((t0, t1))
}

/// Ray–capped-cylinder interval.
fn ray_cylinder(o: V3, d: V3, a: V3, b: V3, r: f64) -> Option<(f64, f64)> {
    let ax = sub(b, a);
    let len = norm(ax);
    let u = scale(ax, 1.0 / len);
    let f = sub(o, a);
    let (h0, dh) = (dot(f, u), dot(d, u));
    // slab 0 ≤ h ≤ len
    let (mut t0, mut t1) = if dh == 0.0 {
        if h0 < 0.0 || h0 > len {
            return None;
        }
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        let p = -h0 / dh;
        let q = (len - h0) / dh;
        (p.min(q), p.max(q))
    };
    let fp = sub(f, scale(u, h0));
    let dp = sub(d, scale(u, dh));
    let l = norm(dp);
    if l == 0.0 {
        if norm(fp) >= r {
            return None;
        }
    } else {
        let (s1, s2) = unit_quadratic(fp, scale(dp, 1.0 / l), r)?;
        t0 = t0.max(s1 / l);
        t1 = t1.min(s2 / l);
    }
    (t0 < t1).then_some((t0, t1))
}

/// Bisect the sign change of `at` on `[lo, hi]` to machine precision.
fn bisect(at: &dyn Fn(f64) -> f64, mut lo: f64, mut hi: f64, inside_lo: bool) -> f64 {
    for _ in 0..64 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if (at(mid) > 0.0) == inside_lo {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Intervals where `F > 0` on `[ta, tb]` (§10.6.2). With `distance_bound` (`|F|` never exceeds
/// the distance to the surface: torus, cone) the walk is sphere tracing, stepping `|F|/|d|`,
/// which cannot jump over the surface; otherwise `steps` uniform samples. Each sign change is
/// bisected to machine precision.
fn ray_roots(
    node: &Node,
    o: V3,
    d: V3,
    ta: f64,
    tb: f64,
    steps: usize,
    distance_bound: bool,
) -> TList {
    let at = |t: f64| node.eval([o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]]);
    let mut out = Vec::new();
    let n = steps.max(2);
    let dt = (tb - ta) / n as f64;
    let dl = norm(d).max(1e-300);
    let min_step = (tb - ta) * 1e-5;
    let mut t_prev = ta;
    let mut f_prev = at(ta);
    let mut start = (f_prev > 0.0).then_some(ta);
    let mut s = 0usize;
    let mut iters = 0usize;
    while t_prev < tb {
        let t = if distance_bound && iters < 100_000 {
            iters += 1;
            (t_prev + (f_prev.abs() / dl).max(min_step)).min(tb)
        } else {
            s += 1;
            let u = ta + s as f64 * dt;
            if s >= n || u >= tb {
                tb
            } else if u <= t_prev {
                continue;
            } else {
                u
            }
        };
        let f = at(t);
        if (f > 0.0) != (f_prev > 0.0) {
            let inside_lo = f_prev > 0.0;
            let root = bisect(&at, t_prev, t, inside_lo);
            if inside_lo {
                if let Some(s0) = start.take() {
                    if root > s0 {
                        out.push((s0, root));
                    }
                }
            } else {
                start = Some(root);
            }
        }
        t_prev = t;
        f_prev = f;
    }
    if let Some(s0) = start {
        if tb > s0 {
            out.push((s0, tb));
        }
    }
    out
}

fn clip(iv: Option<(f64, f64)>, t0: f64, t1: f64) -> TList {
    match iv {
        Some((a, b)) => {
            let (a, b) = (a.max(t0), b.min(t1));
            if a < b {
                vec![(a, b)]
            } else {
                Vec::new()
            }
        }
        None => Vec::new(),
    }
}

/// The t-list of `node` along `o + t d`, restricted to `[t0, t1]`.
pub fn tlist(node: &Node, o: V3, d: V3, t0: f64, t1: f64, steps: usize) -> TList {
    if t0 >= t1 {
        return Vec::new();
    }
    match node {
        Node::Sphere { center, radius } => clip(ray_sphere(o, d, *center, *radius), t0, t1),
        Node::Box { min, max } => clip(ray_box(o, d, *min, *max), t0, t1),
        Node::Cylinder { a, b, radius } => clip(ray_cylinder(o, d, *a, *b, *radius), t0, t1),
        Node::Plane { normal, offset } => {
            let nd = dot(*normal, d);
            let s = offset - dot(*normal, o);
            let iv = if nd == 0.0 {
                (s > 0.0).then_some((f64::NEG_INFINITY, f64::INFINITY))
            } else if nd > 0.0 {
                Some((f64::NEG_INFINITY, s / nd))
            } else {
                Some((s / nd, f64::INFINITY))
            };
            clip(iv, t0, t1)
        }
        Node::Cone { .. } | Node::Torus { .. } | Node::Blend { .. } => {
            let Some((lo, hi)) = node.bounds() else {
                return Vec::new();
            };
            // pad the box slightly so roots on its faces are bracketed
            let pad = 1e-9 * (norm(sub(hi, lo)) + 1.0);
            let lo = [lo[0] - pad, lo[1] - pad, lo[2] - pad];
            let hi = [hi[0] + pad, hi[1] + pad, hi[2] + pad];
            match ray_box(o, d, lo, hi) {
                Some((a, b)) => {
                    let (a, b) = (a.max(t0), b.min(t1));
                    if a < b {
                        ray_roots(node, o, d, a, b, steps, !matches!(node, Node::Blend { .. }))
                    } else {
                        Vec::new()
                    }
                }
                None => Vec::new(),
            }
        }
        Node::Union(c) => {
            let mut acc = Vec::new();
            for n in c {
                let t = tlist(n, o, d, t0, t1, steps);
                acc = if acc.is_empty() { t } else { union(&acc, &t) };
            }
            acc
        }
        Node::Intersection(c) => {
            let mut acc = tlist(&c[0], o, d, t0, t1, steps);
            for n in &c[1..] {
                let Some((lo, hi)) = hull(&acc) else {
                    return acc; // early exit: empty
                };
                acc = intersection(&acc, &tlist(n, o, d, lo, hi, steps));
            }
            acc
        }
        Node::Difference(c) => {
            let mut acc = tlist(&c[0], o, d, t0, t1, steps);
            for n in &c[1..] {
                let Some((lo, hi)) = hull(&acc) else {
                    return acc; // early exit: empty
                };
                acc = difference(&acc, &tlist(n, o, d, lo, hi, steps));
            }
            acc
        }
    }
}

fn hull(t: &[(f64, f64)]) -> Option<(f64, f64)> {
    Some((t.first()?.0, t.last()?.1))
}

/// Default number of rays per side for [`volume`].
pub const DEFAULT_RAYS: usize = 512;

/// Volume of a bounded solid from `rays × rays` parallel rays along `z` through the cell
/// centres of its bounding rectangle: `V ≈ Σ length(t-list) · Δx Δy` (§10.8).
pub fn volume(node: &Node, rays: usize, steps: usize) -> Result<f64> {
    volume_with(node, rays, steps, &crate::progress::Progress::hidden())
}

/// [`volume`], advancing `bar` by one step per row of rays (`rays` steps in all).
pub fn volume_with(
    node: &Node,
    rays: usize,
    steps: usize,
    bar: &crate::progress::Progress,
) -> Result<f64> {
    if rays == 0 {
        return Err(Error::parameter("rays", rays, "at least 1"));
    }
    let (lo, hi) = node.bounds().ok_or_else(|| {
        Error::format(
            "the solid is unbounded",
            "a bounded solid (planes only inside an intersection with a bounded solid)",
        )
    })?;
    if (0..3).any(|i| hi[i].partial_cmp(&lo[i]) != Some(std::cmp::Ordering::Greater)) {
        return Ok(0.0);
    }
    let dx = (hi[0] - lo[0]) / rays as f64;
    let dy = (hi[1] - lo[1]) / rays as f64;
    let total: f64 = (0..rays)
        .into_par_iter()
        .map(|j| {
            let y = lo[1] + (j as f64 + 0.5) * dy;
            let mut s = 0.0;
            for i in 0..rays {
                let x = lo[0] + (i as f64 + 0.5) * dx;
                let t = tlist(
                    node,
                    [x, y, 0.0],
                    [0.0, 0.0, 1.0],
                    lo[2] - 1.0,
                    hi[2] + 1.0,
                    steps,
                );
                s += length(&t);
            }
            bar.inc(1);
            s
        })
        .sum();
    Ok(total * dx * dy)
}

/// First hit `t > t_min` of a ray with the solid, from its t-list.
pub fn first_hit(node: &Node, o: V3, d: V3, t_min: f64, t_max: f64, steps: usize) -> Option<f64> {
    let t = tlist(node, o, d, t_min, t_max, steps);
    t.first().map(|iv| iv.0).filter(|&t| t > t_min)
}

/// A unit vector perpendicular to `u`.
pub fn perpendicular(u: V3) -> V3 {
    let a = if u[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let c = cross(u, a);
    scale(c, 1.0 / norm(c))
}
