//! Implicit primitives and their combination (§10.3–10.5).
//!
//! Every node gives `F(p)`, positive inside. Geometric primitives use the negated
//! (signed) distance, so `|F|` is close to the distance to the surface; skeletal
//! primitives live inside a [`Node::Blend`], whose field is `Σ sᵢ fᵢ(rᵢ) − T` (§10.5).

use crate::mesh::vec3::{add, cross, dot, norm, scale, sub};

type V3 = [f64; 3];

/// Energy function `f(r)` of a skeletal primitive, `r` the distance to its skeleton.
#[derive(Clone, Debug, PartialEq)]
pub enum Falloff {
    /// `f(r) = 1 / r²` (§10.3.3): unbounded support.
    InverseSquare,
    /// Blinn's blobby molecule: `f(r) = exp(−a r²)`.
    Blinn { a: f64 },
    /// Metaball (Nishimura; notes §10.5.1) with support `b`:
    /// `1 − 3r²/b²` for `r ≤ b/3`, `1.5 (1 − r/b)²` for `b/3 ≤ r ≤ b`, `0` beyond.
    Metaball { b: f64 },
    /// Soft object (Wyvill; §10.5.1) with support `R`:
    /// `1 − 4r⁶/9R⁶ + 17r⁴/9R⁴ − 22r²/9R²` for `r ≤ R`, `0` beyond.
    Soft { r: f64 },
}

impl Falloff {
    /// `f(r)`.
    pub fn eval(&self, r: f64) -> f64 {
        match *self {
            Falloff::InverseSquare => 1.0 / (r * r).max(1e-300),
            Falloff::Blinn { a } => (-a * r * r).exp(),
            Falloff::Metaball { b } => {
                if r <= b / 3.0 {
                    1.0 - 3.0 * r * r / (b * b)
                } else if r <= b {
                    1.5 * (1.0 - r / b).powi(2)
                } else {
                    0.0
                }
            }
            Falloff::Soft { r: big } => {
                if r >= big {
                    0.0
                } else {
                    let q = (r * r) / (big * big);
                    1.0 - 4.0 / 9.0 * q * q * q + 17.0 / 9.0 * q * q - 22.0 / 9.0 * q
                }
            }
        }
    }

    /// Distance beyond which `f` is zero (infinite for unbounded falloffs).
    pub fn support(&self) -> f64 {
        match *self {
            Falloff::Metaball { b } => b,
            Falloff::Soft { r } => r,
            _ => f64::INFINITY,
        }
    }
}

/// The skeleton of a skeletal primitive: a point (§10.3.4) or a segment (§10.3.5).
#[derive(Clone, Debug, PartialEq)]
pub enum Bone {
    Point(V3),
    Segment(V3, V3),
}

impl Bone {
    /// Distance from `p` to the skeleton.
    pub fn distance(&self, p: V3) -> f64 {
        match *self {
            Bone::Point(c) => norm(sub(p, c)),
            Bone::Segment(a, b) => segment_distance(p, a, b),
        }
    }
}

/// A skeletal primitive: `strength · f(distance to bone)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Skeleton {
    pub bone: Bone,
    pub falloff: Falloff,
    pub strength: f64,
}

/// A node of an implicit model / CSG tree.
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    /// `F = r − |p − c|`.
    Sphere { center: V3, radius: f64 },
    /// Axis-aligned box `[min, max]`, `F = −sdf`.
    Box { min: V3, max: V3 },
    /// Capped cylinder of radius `radius` around the segment `a → b`, `F = −sdf`.
    Cylinder { a: V3, b: V3, radius: f64 },
    /// Capped cone from radius `ra` at `a` to radius `rb` at `b` (`F` has the right sign and
    /// zero set; its magnitude is the distance to the nearest of lateral surface and caps).
    Cone { a: V3, b: V3, ra: f64, rb: f64 },
    /// Torus around the axis through `center` along `axis`: `F = minor − |(ρ − major, h)|`.
    Torus {
        center: V3,
        axis: V3,
        major: f64,
        minor: f64,
    },
    /// Half-space `n·p ≤ d` (`n` unit): `F = d − n·p`.
    Plane { normal: V3, offset: f64 },
    /// `F = Σ sᵢ fᵢ(rᵢ) − T` (§10.5; with metaball or soft falloffs the better blend of §10.5.1).
    Blend {
        threshold: f64,
        items: Vec<Skeleton>,
    },
    /// `F = max Fᵢ` (§10.4).
    Union(Vec<Node>),
    /// `F = min Fᵢ`.
    Intersection(Vec<Node>),
    /// `F = min(F₀, −F₁, −F₂, …)`.
    Difference(Vec<Node>),
}

/// Distance from `p` to the segment `a b`.
pub fn segment_distance(p: V3, a: V3, b: V3) -> f64 {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    let t = if l2 > 0.0 {
        (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    norm(sub(p, add(a, scale(ab, t))))
}

/// Axial coordinate `h ∈ ℝ` (0 at `a`) and radial distance of `p` for the axis `a → b`.
fn axial(p: V3, a: V3, b: V3) -> (f64, f64, f64) {
    let ab = sub(b, a);
    let len = norm(ab);
    let u = scale(ab, 1.0 / len.max(1e-300));
    let ap = sub(p, a);
    let h = dot(ap, u);
    let rho = norm(cross(ap, u));
    (h, rho, len)
}

/// `−sdf` of a 2-D rectangle-like region given the two signed excesses (`> 0` outside).
fn neg_sdf2(dx: f64, dy: f64) -> f64 {
    let inside = dx.max(dy).min(0.0);
    let ox = dx.max(0.0);
    let oy = dy.max(0.0);
    -(inside + (ox * ox + oy * oy).sqrt())
}

impl Node {
    /// `F(p)`, positive inside.
    pub fn eval(&self, p: V3) -> f64 {
        match self {
            Node::Sphere { center, radius } => radius - norm(sub(p, *center)),
            Node::Box { min, max } => {
                let mut q = [0.0; 3];
                for i in 0..3 {
                    let c = 0.5 * (min[i] + max[i]);
                    let h = 0.5 * (max[i] - min[i]);
                    q[i] = (p[i] - c).abs() - h;
                }
                let outside = norm([q[0].max(0.0), q[1].max(0.0), q[2].max(0.0)]);
                let inside = q[0].max(q[1]).max(q[2]).min(0.0);
                -(outside + inside)
            }
            Node::Cylinder { a, b, radius } => {
                let (h, rho, len) = axial(p, *a, *b);
                neg_sdf2(rho - radius, (h - 0.5 * len).abs() - 0.5 * len)
            }
            Node::Cone { a, b, ra, rb } => {
                let (h, rho, len) = axial(p, *a, *b);
                let cap = (h - 0.5 * len).abs() - 0.5 * len;
                // lateral: distance to the line through (ra, 0) and (rb, len) in (ρ, h)
                let (dr, dh) = (rb - ra, len);
                let l = (dr * dr + dh * dh).sqrt();
                let lateral = ((rho - ra) * dh - h * dr) / l;
                -(cap.max(lateral))
            }
            Node::Torus {
                center,
                axis,
                major,
                minor,
            } => {
                let n = scale(*axis, 1.0 / norm(*axis).max(1e-300));
                let d = sub(p, *center);
                let h = dot(d, n);
                let rho = norm(cross(d, n));
                minor - ((rho - major).powi(2) + h * h).sqrt()
            }
            Node::Plane { normal, offset } => offset - dot(*normal, p),
            Node::Blend { threshold, items } => {
                let mut s = 0.0;
                for it in items {
                    s += it.strength * it.falloff.eval(it.bone.distance(p));
                }
                s - threshold
            }
            Node::Union(c) => c
                .iter()
                .map(|n| n.eval(p))
                .fold(f64::NEG_INFINITY, f64::max),
            Node::Intersection(c) => c.iter().map(|n| n.eval(p)).fold(f64::INFINITY, f64::min),
            Node::Difference(c) => {
                let mut f = c[0].eval(p);
                for n in &c[1..] {
                    f = f.min(-n.eval(p));
                }
                f
            }
        }
    }

    /// Point membership: `F(p) > 0`.
    pub fn contains(&self, p: V3) -> bool {
        self.eval(p) > 0.0
    }

    /// `∇F` by central differences with step `h` (§10.3.2).
    pub fn gradient(&self, p: V3, h: f64) -> V3 {
        let mut g = [0.0; 3];
        for i in 0..3 {
            let mut a = p;
            let mut b = p;
            a[i] += h;
            b[i] -= h;
            g[i] = (self.eval(a) - self.eval(b)) / (2.0 * h);
        }
        g
    }

    /// Outward unit normal `−∇F/|∇F|` (F grows inwards); `None` at a singular point.
    pub fn normal(&self, p: V3, h: f64) -> Option<V3> {
        let g = self.gradient(p, h);
        let n = norm(g);
        (n > 0.0 && n.is_finite()).then(|| scale(g, -1.0 / n))
    }

    /// An axis-aligned box containing the solid, `None` when unbounded.
    pub fn bounds(&self) -> Option<(V3, V3)> {
        match self {
            Node::Sphere { center, radius } => {
                Some((sub(*center, [*radius; 3]), add(*center, [*radius; 3])))
            }
            Node::Box { min, max } => Some((*min, *max)),
            Node::Cylinder { a, b, radius } => Some(capsule_box(*a, *b, *radius)),
            Node::Cone { a, b, ra, rb } => Some(capsule_box(*a, *b, ra.max(*rb))),
            Node::Torus {
                center,
                major,
                minor,
                ..
            } => {
                let r = major + minor;
                Some((sub(*center, [r; 3]), add(*center, [r; 3])))
            }
            Node::Plane { .. } => None,
            Node::Blend { threshold, items } => {
                let mut lo = [f64::INFINITY; 3];
                let mut hi = [f64::NEG_INFINITY; 3];
                for it in items {
                    let reach = skeleton_reach(it, *threshold)?;
                    let (a, b) = match it.bone {
                        Bone::Point(c) => (c, c),
                        Bone::Segment(a, b) => (a, b),
                    };
                    for i in 0..3 {
                        lo[i] = lo[i].min(a[i].min(b[i]) - reach);
                        hi[i] = hi[i].max(a[i].max(b[i]) + reach);
                    }
                }
                (lo[0] <= hi[0]).then_some((lo, hi))
            }
            Node::Union(c) => {
                let mut acc: Option<(V3, V3)> = None;
                for n in c {
                    let (lo, hi) = n.bounds()?;
                    acc = Some(match acc {
                        None => (lo, hi),
                        Some((a, b)) => (
                            [a[0].min(lo[0]), a[1].min(lo[1]), a[2].min(lo[2])],
                            [b[0].max(hi[0]), b[1].max(hi[1]), b[2].max(hi[2])],
                        ),
                    });
                }
                acc
            }
            Node::Intersection(c) => {
                let mut acc: Option<(V3, V3)> = None;
                for n in c {
                    if let Some((lo, hi)) = n.bounds() {
                        acc = Some(match acc {
                            None => (lo, hi),
                            Some((a, b)) => (
                                [a[0].max(lo[0]), a[1].max(lo[1]), a[2].max(lo[2])],
                                [b[0].min(hi[0]), b[1].min(hi[1]), b[2].min(hi[2])],
                            ),
                        });
                    }
                }
                acc
            }
            Node::Difference(c) => c[0].bounds(),
        }
    }

    /// Number of leaves (primitives and blends) in the tree.
    pub fn leaf_count(&self) -> usize {
        match self {
            Node::Union(c) | Node::Intersection(c) | Node::Difference(c) => {
                c.iter().map(Node::leaf_count).sum()
            }
            _ => 1,
        }
    }
}

/// Box around a capsule `a b` of radius `r`.
fn capsule_box(a: V3, b: V3, r: f64) -> (V3, V3) {
    let mut lo = [0.0; 3];
    let mut hi = [0.0; 3];
    for i in 0..3 {
        lo[i] = a[i].min(b[i]) - r;
        hi[i] = a[i].max(b[i]) + r;
    }
    (lo, hi)
}

/// Distance beyond which one skeleton alone cannot reach the threshold: its support, or for
/// unbounded falloffs the distance where `s f(r)` drops to 1e-3 of the threshold.
fn skeleton_reach(s: &Skeleton, threshold: f64) -> Option<f64> {
    let sup = s.falloff.support();
    if sup.is_finite() {
        return Some(sup);
    }
    let target = 1e-3 * threshold.abs().max(1e-12) / s.strength.abs().max(1e-300);
    match s.falloff {
        Falloff::InverseSquare => Some(1.0 / target.sqrt()),
        Falloff::Blinn { a } => (a > 0.0 && target < 1.0).then(|| (-target.ln() / a).sqrt()),
        _ => None,
    }
}
