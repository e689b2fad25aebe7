//! The JSON scene format. A scene is one object:
//!
//! ```json
//! {
//!   "defs": { "peg": { "type": "cylinder", "a": [0,0,-2], "b": [0,0,2], "radius": 0.4 } },
//!   "root": { "type": "difference", "children": [
//!       { "type": "box", "min": [-1,-1,-1], "max": [1,1,1] },
//!       { "ref": "peg" } ] },
//!   "camera": { "eye": [3,2,4], "target": [0,0,0], "fov": 40 },
//!   "light": [4,5,6]
//! }
//! ```
//!
//! Node types: `sphere {center, radius}`, `box {min, max}` or `{center, size}`,
//! `cylinder {a, b, radius}`, `cone {a, b, ra, rb}`, `torus {center, axis?, major, minor}`,
//! `plane {normal, offset}` (inside is `normal·p ≤ offset`), `union|intersection|difference
//! {children}`, `blend {threshold, items}` with items `{point: [x,y,z]}` or
//! `{segment: [[..],[..]]}`, `falloff: "inverse_square" | "blinn" | "metaball" | "soft"`,
//! `a` (Blinn), `support` (metaball / soft), `strength` (default 1), and `{ref: name}` naming
//! an entry of `defs`. Errors name the place, e.g. `root.children[1]: unknown primitive "sphre"`.

use super::field::{Bone, Falloff, Node, Skeleton};
use crate::{Error, Result};
use serde_json::{Map, Value};
use std::collections::HashMap;

/// Camera and light of a scene (for rendering).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    /// Vertical field of view in degrees.
    pub fov: f64,
}

/// A parsed scene: the model tree plus viewing parameters.
#[derive(Clone, Debug)]
pub struct Scene {
    pub root: Node,
    pub camera: Option<Camera>,
    pub light: Option<[f64; 3]>,
}

fn err(place: &str, msg: impl std::fmt::Display) -> Error {
    Error::format(
        format!("{place}: {msg}"),
        "a valid scene (see docs/solid.md)",
    )
}

impl Scene {
    /// Parse a scene from JSON text.
    pub fn parse(text: &str) -> Result<Scene> {
        let v: Value = serde_json::from_str(text).map_err(|e| {
            Error::format(
                format!("scene JSON: {e}"),
                "a JSON object with a \"root\" node",
            )
        })?;
        let obj = v
            .as_object()
            .ok_or_else(|| err("scene", "not a JSON object"))?;
        let defs = match obj.get("defs") {
            None => Map::new(),
            Some(Value::Object(m)) => m.clone(),
            Some(_) => return Err(err("defs", "not an object of named nodes")),
        };
        let root = obj
            .get("root")
            .ok_or_else(|| err("scene", "no \"root\" node"))?;
        let mut p = Parser {
            defs: &defs,
            stack: Vec::new(),
            done: HashMap::new(),
        };
        let root = p.node(root, "root")?;
        let camera = match obj.get("camera") {
            None => None,
            Some(c) => {
                let o = c
                    .as_object()
                    .ok_or_else(|| err("camera", "not an object"))?;
                Some(Camera {
                    eye: vec3(o, "eye", "camera")?,
                    target: opt_vec3(o, "target", "camera")?.unwrap_or([0.0; 3]),
                    up: opt_vec3(o, "up", "camera")?.unwrap_or([0.0, 1.0, 0.0]),
                    fov: opt_num(o, "fov", "camera")?.unwrap_or(40.0),
                })
            }
        };
        let light = match obj.get("light") {
            None => None,
            Some(l) => Some(to_vec3(l, "light")?),
        };
        Ok(Scene {
            root,
            camera,
            light,
        })
    }

    /// Read and parse a scene file.
    pub fn read(path: &std::path::Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path)?;
        Scene::parse(&text)
    }
}

struct Parser<'a> {
    defs: &'a Map<String, Value>,
    stack: Vec<String>,
    done: HashMap<String, Node>,
}

/// A JSON array of three finite numbers; the error is `None` when `v` is not an array of
/// three, `Some(d)` when element `d` is not a finite number.
pub(crate) fn finite3(v: &Value) -> std::result::Result<[f64; 3], Option<usize>> {
    let a = v.as_array().filter(|a| a.len() == 3).ok_or(None)?;
    let mut out = [0.0; 3];
    for (d, x) in a.iter().enumerate() {
        out[d] = x.as_f64().filter(|x| x.is_finite()).ok_or(Some(d))?;
    }
    Ok(out)
}

fn to_vec3(v: &Value, place: &str) -> Result<[f64; 3]> {
    finite3(v).map_err(|_| err(place, "not an array of three numbers"))
}

fn opt_vec3(o: &Map<String, Value>, key: &str, place: &str) -> Result<Option<[f64; 3]>> {
    o.get(key)
        .map(|v| to_vec3(v, &format!("{place}.{key}")))
        .transpose()
}

fn vec3(o: &Map<String, Value>, key: &str, place: &str) -> Result<[f64; 3]> {
    opt_vec3(o, key, place)?.ok_or_else(|| err(place, format!("missing \"{key}\"")))
}

fn opt_num(o: &Map<String, Value>, key: &str, place: &str) -> Result<Option<f64>> {
    match o.get(key) {
        None => Ok(None),
        Some(v) => v
            .as_f64()
            .filter(|x| x.is_finite())
            .map(Some)
            .ok_or_else(|| err(&format!("{place}.{key}"), "not a finite number")),
    }
}

fn num(o: &Map<String, Value>, key: &str, place: &str) -> Result<f64> {
    opt_num(o, key, place)?.ok_or_else(|| err(place, format!("missing \"{key}\"")))
}

/// A length that must be `> 0` (radii, supports).
fn positive(o: &Map<String, Value>, key: &str, place: &str) -> Result<f64> {
    let x = num(o, key, place)?;
    if x <= 0.0 {
        return Err(err(
            &format!("{place}.{key}"),
            format!("{x} is not a positive length"),
        ));
    }
    Ok(x)
}

impl Parser<'_> {
    fn node(&mut self, v: &Value, place: &str) -> Result<Node> {
        let o = v
            .as_object()
            .ok_or_else(|| err(place, "a node must be a JSON object"))?;
        if let Some(r) = o.get("ref") {
            return self.reference(r, place);
        }
        let ty = o
            .get("type")
            .and_then(Value::as_str)
            .ok_or_else(|| err(place, "missing \"type\" (or \"ref\")"))?;
        Ok(match ty {
            "blend" => blend(o, place)?,
            "union" | "intersection" | "difference" => self.csg(o, ty, place)?,
            _ => primitive(o, ty, place)?,
        })
    }

    /// A `{"ref": name}` node: the definition parsed once, cycles refused.
    fn reference(&mut self, r: &Value, place: &str) -> Result<Node> {
        let name = r
            .as_str()
            .ok_or_else(|| err(place, "\"ref\" must be a name"))?;
        if let Some(n) = self.done.get(name) {
            return Ok(n.clone());
        }
        if self.stack.iter().any(|s| s == name) {
            let mut cycle = self.stack.clone();
            cycle.push(name.to_string());
            return Err(err(
                place,
                format!("cyclic reference {}", cycle.join(" -> ")),
            ));
        }
        let def = self
            .defs
            .get(name)
            .ok_or_else(|| err(place, format!("unknown reference \"{name}\"")))?;
        self.stack.push(name.to_string());
        let n = self.node(def, &format!("defs.{name}"))?;
        self.stack.pop();
        self.done.insert(name.to_string(), n.clone());
        Ok(n)
    }

    /// A Boolean node over its `children`.
    fn csg(&mut self, o: &Map<String, Value>, ty: &str, place: &str) -> Result<Node> {
        let ch = o
            .get("children")
            .and_then(Value::as_array)
            .ok_or_else(|| err(place, "missing \"children\" array"))?;
        if ch.is_empty() {
            return Err(err(place, format!("empty {ty}")));
        }
        let mut out = Vec::new();
        for (i, c) in ch.iter().enumerate() {
            out.push(self.node(c, &format!("{place}.children[{i}]"))?);
        }
        Ok(match ty {
            "union" => Node::Union(out),
            "intersection" => Node::Intersection(out),
            _ => Node::Difference(out),
        })
    }
}

/// A primitive node of type `ty`.
fn primitive(o: &Map<String, Value>, ty: &str, place: &str) -> Result<Node> {
    Ok(match ty {
        "sphere" => Node::Sphere {
            center: opt_vec3(o, "center", place)?.unwrap_or([0.0; 3]),
            radius: positive(o, "radius", place)?,
        },
        "box" => {
            let (min, max) = if o.contains_key("min") {
                (vec3(o, "min", place)?, vec3(o, "max", place)?)
            } else {
                let c = opt_vec3(o, "center", place)?.unwrap_or([0.0; 3]);
                let s = vec3(o, "size", place)?;
                (
                    [c[0] - s[0] / 2.0, c[1] - s[1] / 2.0, c[2] - s[2] / 2.0],
                    [c[0] + s[0] / 2.0, c[1] + s[1] / 2.0, c[2] + s[2] / 2.0],
                )
            };
            if (0..3).any(|i| max[i] <= min[i]) {
                return Err(err(place, "box with max ≤ min on some axis"));
            }
            Node::Box { min, max }
        }
        "cylinder" => {
            let (a, b) = (vec3(o, "a", place)?, vec3(o, "b", place)?);
            distinct(a, b, place)?;
            Node::Cylinder {
                a,
                b,
                radius: positive(o, "radius", place)?,
            }
        }
        "cone" => {
            let (a, b) = (vec3(o, "a", place)?, vec3(o, "b", place)?);
            distinct(a, b, place)?;
            let ra = num(o, "ra", place)?;
            let rb = num(o, "rb", place)?;
            if ra < 0.0 || rb < 0.0 || ra + rb <= 0.0 {
                return Err(err(place, "cone radii must be ≥ 0 and not both 0"));
            }
            Node::Cone { a, b, ra, rb }
        }
        "torus" => {
            let major = positive(o, "major", place)?;
            let minor = positive(o, "minor", place)?;
            let axis = opt_vec3(o, "axis", place)?.unwrap_or([0.0, 0.0, 1.0]);
            if axis == [0.0; 3] {
                return Err(err(&format!("{place}.axis"), "zero vector"));
            }
            Node::Torus {
                center: opt_vec3(o, "center", place)?.unwrap_or([0.0; 3]),
                axis,
                major,
                minor,
            }
        }
        "plane" => {
            let n = vec3(o, "normal", place)?;
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if l == 0.0 {
                return Err(err(&format!("{place}.normal"), "zero vector"));
            }
            Node::Plane {
                normal: [n[0] / l, n[1] / l, n[2] / l],
                offset: opt_num(o, "offset", place)?.unwrap_or(0.0) / l,
            }
        }
        other => return Err(err(place, format!("unknown primitive \"{other}\""))),
    })
}

/// A blend of skeletal fields (§10.5) minus a threshold.
fn blend(o: &Map<String, Value>, place: &str) -> Result<Node> {
    let items = o
        .get("items")
        .and_then(Value::as_array)
        .ok_or_else(|| err(place, "missing \"items\" array"))?;
    if items.is_empty() {
        return Err(err(place, "empty blend"));
    }
    let mut out = Vec::new();
    for (i, it) in items.iter().enumerate() {
        out.push(skeleton(it, &format!("{place}.items[{i}]"))?);
    }
    Ok(Node::Blend {
        threshold: num(o, "threshold", place)?,
        items: out,
    })
}

fn distinct(a: [f64; 3], b: [f64; 3], place: &str) -> Result<()> {
    if a == b {
        return Err(err(place, "axis end points a and b coincide"));
    }
    Ok(())
}

fn skeleton(v: &Value, place: &str) -> Result<Skeleton> {
    let o = v
        .as_object()
        .ok_or_else(|| err(place, "a blend item must be an object"))?;
    let bone = if let Some(p) = o.get("point") {
        Bone::Point(to_vec3(p, &format!("{place}.point"))?)
    } else if let Some(s) = o.get("segment") {
        let a = s
            .as_array()
            .filter(|a| a.len() == 2)
            .ok_or_else(|| err(place, "\"segment\" must be two points"))?;
        Bone::Segment(
            to_vec3(&a[0], &format!("{place}.segment[0]"))?,
            to_vec3(&a[1], &format!("{place}.segment[1]"))?,
        )
    } else {
        return Err(err(place, "blend item needs \"point\" or \"segment\""));
    };
    let falloff = match o.get("falloff").and_then(Value::as_str).unwrap_or("soft") {
        "inverse_square" => Falloff::InverseSquare,
        "blinn" => Falloff::Blinn {
            a: positive(o, "a", place)?,
        },
        "metaball" => Falloff::Metaball {
            b: positive(o, "support", place)?,
        },
        "soft" => Falloff::Soft {
            r: positive(o, "support", place)?,
        },
        f => return Err(err(place, format!("unknown falloff \"{f}\""))),
    };
    Ok(Skeleton {
        bone,
        falloff,
        strength: opt_num(o, "strength", place)?.unwrap_or(1.0),
    })
}
