//! The module map of `src/lib.rs`, checked: the map names every top-level module of
//! `src/` with its layer; every `crate::…` and `super::…` path in `src/` names a module of
//! a lower layer, or of the same layer where [`SAME_LAYER`] lists the pair; and no modules
//! import each other round in a cycle (neither the top-level modules, nor the files, a
//! module and its own submodules apart). An import that breaks the map fails here with
//! the file and path.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The layers as `src/lib.rs`'s map gives them: `(module, layer)`, read from the lines
/// `//! <layer>  src/<module>/ …` or `//! <layer>  src/<module>.rs …` of its `text` block.
fn parse_map(lib_rs: &str) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    for line in lib_rs.lines() {
        let Some(rest) = line.strip_prefix("//!") else {
            continue;
        };
        let mut words = rest.split_whitespace();
        let (Some(layer), Some(path)) = (words.next(), words.next()) else {
            continue;
        };
        let (Ok(layer), Some(path)) = (layer.parse::<usize>(), path.strip_prefix("src/")) else {
            continue;
        };
        let name = path.trim_end_matches('/').trim_end_matches(".rs");
        out.push((name.to_string(), layer));
    }
    out
}

fn map() -> &'static [(String, usize)] {
    static MAP: OnceLock<Vec<(String, usize)>> = OnceLock::new();
    MAP.get_or_init(|| {
        let lib = std::fs::read_to_string(src().join("lib.rs")).expect("read src/lib.rs");
        parse_map(&lib)
    })
}

/// Imports between two modules of one layer that the map allows: `(from, to)`, each with
/// why. Any other import within a layer fails, as an upward one does.
const SAME_LAYER: &[(&str, &str, &str)] = &[
    (
        "kernel",
        "scheme",
        "the kernels apply the schemes' operators",
    ),
    (
        "limits",
        "tuning",
        "the budget's variable is read where every variable is",
    ),
    ("metrics", "io", "PSNR of files compares rasters as read"),
    ("generate", "io", "generated rasters are io's raster types"),
    ("demo", "generate", "the demo runs on generated data"),
    (
        "codec",
        "entropy",
        "the codec codes bands with the coefficient coders",
    ),
    ("codec", "quantize", "the codec quantizes bands"),
    ("surface", "curve", "surfaces are built from curves"),
    ("surface", "mesh", "surfaces are tessellated into meshes"),
    ("solid", "curve", "swept and revolved solids follow curves"),
    ("solid", "mesh", "solids are polygonised into meshes"),
    ("points", "curve", "point lists are curves' control points"),
    ("upscale", "curve", "the upscaler's edge curves"),
];

/// Imports the map does not allow yet, each with why it stays: `(from, to)` as module
/// paths (a top-level module, or a file's module).
const EXCEPTIONS: &[(&str, &str, &str)] = &[
    // the curve plots draw on the surface module's canvas while surfaces are built from
    // curves: a shared raster type belongs below both (geometry, a later round)
    (
        "curve::plot",
        "surface::raster",
        "shared canvas of the geometry plots",
    ),
];

/// The layer of a top-level module (`None`: a module the map does not name).
fn layer(room: &str) -> Option<usize> {
    map().iter().find(|(m, _)| m == room).map(|&(_, l)| l)
}

/// Why an import from top-level module `a` to `b` breaks the map, if it does.
fn breaks_map(a: &str, b: &str, layer: &dyn Fn(&str) -> Option<usize>) -> Option<String> {
    match (layer(a), layer(b)) {
        (Some(la), Some(lb)) if lb > la => Some(format!("(layer {la}) uses a layer above, {lb}")),
        (Some(la), Some(lb))
            if lb == la && a != b && !SAME_LAYER.iter().any(|&(x, y, _)| x == a && y == b) =>
        {
            Some(format!(
                "(layer {la}) uses its own layer's {b}, a pair SAME_LAYER does not list"
            ))
        }
        (None, _) | (_, None) => Some(format!(
            "a module missing from src/lib.rs's map: {a} or {b}"
        )),
        _ => None,
    }
}

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every `.rs` file under `dir`.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("read src/") {
        let p = e.expect("dir entry").path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The module path of a file: `src/kernel/x86/avx2.rs` → `["kernel", "x86", "avx2"]`,
/// `src/kernel/mod.rs` → `["kernel"]`, `src/lib.rs` → `[]`.
fn module_of(file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src()).expect("under src/");
    let mut parts: Vec<String> = rel
        .iter()
        .map(|c| c.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") {
        parts.push(stem.to_string());
    }
    parts
}

/// The code of a file without comments and string literals (doc comments mention paths
/// that are not imports).
fn code(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let mut in_str = false;
        let mut prev = ' ';
        let mut chars = line.chars().peekable();
        while let Some(c) = chars.next() {
            if !in_str && c == '/' && chars.peek() == Some(&'/') {
                break;
            }
            if c == '"' && prev != '\\' && prev != '\'' {
                in_str = !in_str;
            } else if !in_str {
                out.push(c);
            }
            prev = c;
        }
        out.push('\n');
    }
    out
}

/// The paths named after `crate::` and `super::` in `code`, as segments from the crate
/// root (`super` resolved against `module`, the file's module: a `mod.rs` is its
/// directory's module, so its `super` is the directory's parent). Braced groups are
/// expanded one level: `crate::io::{self, png}` → `io`, `io::png`.
fn paths(code: &str, module: &[String]) -> Vec<Vec<String>> {
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let bytes: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let starts_word = i == 0 || !(ident(bytes[i - 1]) || bytes[i - 1] == ':');
        let rest: String = bytes[i..(i + 7).min(bytes.len())].iter().collect();
        let (base, skip) = if starts_word && rest.starts_with("crate::") {
            (Vec::new(), 7)
        } else if starts_word && rest.starts_with("super::") {
            // the parent of this file's module (a mod.rs is its directory's module)
            let mut b = module.to_vec();
            b.pop();
            let mut j = i + 7;
            // more `super::`
            loop {
                let r: String = bytes[j..(j + 7).min(bytes.len())].iter().collect();
                if r == "super::" {
                    b.pop();
                    j += 7;
                } else {
                    break;
                }
            }
            (b, j - i)
        } else {
            i += 1;
            continue;
        };
        let mut j = i + skip;
        // a path of identifiers, then maybe a braced group
        let mut segs = base.clone();
        loop {
            if j < bytes.len() && bytes[j] == '{' {
                // the group's items, one level
                let mut depth = 0;
                let mut item = String::new();
                let mut items = Vec::new();
                while j < bytes.len() {
                    let c = bytes[j];
                    j += 1;
                    match c {
                        '{' => {
                            depth += 1;
                            if depth > 1 {
                                item.push(c);
                            }
                        }
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                items.push(std::mem::take(&mut item));
                                break;
                            }
                            item.push(c);
                        }
                        ',' if depth == 1 => items.push(std::mem::take(&mut item)),
                        _ => item.push(c),
                    }
                }
                for it in items {
                    let mut p = segs.clone();
                    for s in it.split("::") {
                        let s = s.trim();
                        if s.is_empty() || !s.chars().all(ident) {
                            break;
                        }
                        if s != "self" {
                            p.push(s.to_string());
                        }
                    }
                    out.push(p);
                }
                segs.clear();
                break;
            }
            let s = j;
            while j < bytes.len() && ident(bytes[j]) {
                j += 1;
            }
            if j > s {
                segs.push(bytes[s..j].iter().collect());
            }
            if j + 1 < bytes.len() && bytes[j] == ':' && bytes[j + 1] == ':' {
                j += 2;
                continue;
            }
            break;
        }
        if !segs.is_empty() {
            out.push(segs);
        }
        i = j.max(i + 1);
    }
    out
}

struct Graph {
    /// file module → the file modules it names.
    files: BTreeMap<String, BTreeSet<String>>,
    /// (from file, the path as written) → for messages.
    upward: Vec<String>,
    /// The pairs of top-level modules some file imports across.
    rooms: BTreeSet<(String, String)>,
}

fn build() -> Graph {
    let mut all = Vec::new();
    files(&src(), &mut all);
    all.sort();
    let modules: BTreeSet<Vec<String>> = all.iter().map(|f| module_of(f)).collect();
    let mut g = Graph {
        files: BTreeMap::new(),
        upward: Vec::new(),
        rooms: BTreeSet::new(),
    };
    for f in &all {
        let m = module_of(f);
        if m.is_empty() || f.ends_with("main.rs") {
            continue; // the crate root declares everything
        }
        let text = std::fs::read_to_string(f).expect("read a source file");
        let from = m.join("::");
        let entry = g.files.entry(from.clone()).or_default();
        for p in paths(&code(&text), &m) {
            // the longest prefix of the path that is a module with a file
            let Some(target) = (1..=p.len())
                .rev()
                .map(|n| p[..n].to_vec())
                .find(|q| modules.contains(q))
            else {
                continue; // an item of the crate root (`crate::Error`, `crate::Result`)
            };
            let to = target.join("::");
            if to == from {
                continue;
            }
            let (a, b) = (&m[0], &target[0]);
            let allowed = EXCEPTIONS
                .iter()
                .any(|&(x, y, _)| from.starts_with(x) && to.starts_with(y));
            if a != b {
                g.rooms.insert((a.clone(), b.clone()));
            }
            if a != b && !allowed {
                if let Some(why) = breaks_map(a, b, &layer) {
                    g.upward
                        .push(format!("{} uses {}: {why}", f.display(), p.join("::")));
                }
            }
            if !allowed {
                entry.insert(to);
            }
        }
    }
    g
}

/// Whether `a` is `b` or inside it, or the other way round (a module and its
/// submodules share their items through `super::` and `pub use`; that is not a cycle).
fn nested(a: &str, b: &str) -> bool {
    let inside = |x: &str, y: &str| x == y || x.starts_with(&format!("{y}::"));
    inside(a, b) || inside(b, a)
}

/// A cycle of `edges` (as the nodes along it), if any.
fn cycle(edges: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    // depth-first search with colours: 0 new, 1 on the stack, 2 done
    fn visit(
        n: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        colour: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        colour.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for m in edges.get(n).into_iter().flatten() {
            match colour.get(m.as_str()).copied().unwrap_or(0) {
                1 => {
                    let at = stack.iter().position(|s| s == m).expect("on the stack");
                    let mut c = stack[at..].to_vec();
                    c.push(m.clone());
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(m, edges, colour, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        colour.insert(n.to_string(), 2);
        None
    }
    let mut colour = BTreeMap::new();
    for n in edges.keys() {
        if colour.get(n.as_str()).copied().unwrap_or(0) == 0 {
            let mut stack = Vec::new();
            if let Some(c) = visit(n, edges, &mut colour, &mut stack) {
                return Some(c);
            }
        }
    }
    None
}

/// The top-level modules of `src/`: its folders and its files but `lib.rs` and `main.rs`.
fn top_level_modules() -> BTreeSet<String> {
    std::fs::read_dir(src())
        .expect("read src/")
        .map(|e| e.expect("dir entry").path())
        .filter_map(|p| {
            let name = p.file_name()?.to_string_lossy().into_owned();
            if p.is_dir() {
                Some(name)
            } else {
                let stem = name.strip_suffix(".rs")?;
                (!matches!(stem, "lib" | "main")).then(|| stem.to_string())
            }
        })
        .collect()
}

#[test]
fn the_module_map_names_every_module_of_src_once() {
    let named: Vec<&str> = map().iter().map(|(m, _)| m.as_str()).collect();
    let set: BTreeSet<String> = named.iter().map(|m| m.to_string()).collect();
    assert_eq!(
        set.len(),
        named.len(),
        "a module named twice in src/lib.rs's map"
    );
    assert_eq!(
        set,
        top_level_modules(),
        "src/lib.rs's map against the folders and files of src/"
    );
    for (m, l) in map() {
        let declared = format!("pub mod {m};");
        let lib = std::fs::read_to_string(src().join("lib.rs")).expect("read src/lib.rs");
        assert!(
            lib.contains(&declared) || lib.contains(&format!("mod {m};")),
            "{m} (layer {l}) is in the map but not declared in src/lib.rs"
        );
    }
    for &(a, b, _) in SAME_LAYER {
        assert_eq!(
            layer(a),
            layer(b),
            "SAME_LAYER lists {a} → {b} of two layers"
        );
    }
}

#[test]
fn the_readme_layout_names_every_module() {
    let readme = std::fs::read_to_string(src().join("../README.md")).expect("read README.md");
    let start = readme
        .find("## Layout")
        .expect("README.md has a Layout section");
    let block = &readme[start..];
    for m in top_level_modules() {
        let dir = format!("src/{m}/");
        let file = format!("src/{m}.rs");
        assert!(
            block.contains(&dir) || block.contains(&file),
            "README.md's Layout does not name {dir} or {file}"
        );
    }
}

#[test]
fn the_map_parser_reads_layers_and_paths() {
    let text = "//! ```text\n//! layer  module  job\n//! 0      src/error.rs   e\n\
                //! 4      src/codec/     c\n//! not a row\n";
    assert_eq!(
        parse_map(text),
        [("error".to_string(), 0), ("codec".to_string(), 4)]
    );
}

#[test]
fn no_module_uses_a_layer_above_its_own() {
    let g = build();
    assert!(
        g.upward.is_empty(),
        "imports that break src/lib.rs's module map:\n{}",
        g.upward.join("\n")
    );
    for &(a, b, why) in SAME_LAYER {
        assert!(
            g.rooms.contains(&(a.to_string(), b.to_string())),
            "SAME_LAYER allows {a} → {b} ({why}), which no file imports: remove it"
        );
    }
}

#[test]
fn the_top_level_modules_import_each_other_in_no_cycle() {
    let g = build();
    let mut rooms: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (from, tos) in &g.files {
        let a = from.split("::").next().unwrap_or_default().to_string();
        for to in tos {
            let b = to.split("::").next().unwrap_or_default().to_string();
            if a != b {
                rooms.entry(a.clone()).or_default().insert(b);
            }
        }
    }
    assert_eq!(cycle(&rooms), None, "a cycle between top-level modules");
}

#[test]
fn the_files_import_each_other_in_no_cycle() {
    let g = build();
    let edges: BTreeMap<String, BTreeSet<String>> = g
        .files
        .iter()
        .map(|(a, tos)| {
            let keep = tos.iter().filter(|b| !nested(a, b)).cloned().collect();
            (a.clone(), keep)
        })
        .collect();
    assert_eq!(cycle(&edges), None, "a cycle between files");
}

#[test]
fn the_checker_sees_imports_and_cycles() {
    // a made-up file `src/kernel/pair.rs` naming a tensor path and a scheme path
    let m = vec!["kernel".to_string(), "pair".to_string()];
    let c = code(
        "use crate::tensor::par::SharedMut; // crate::cli in a comment\n\
         use super::{combine, layout::transpose};\nlet s = \"crate::io\";\n",
    );
    let p = paths(&c, &m);
    let joined: Vec<String> = p.iter().map(|q| q.join("::")).collect();
    assert_eq!(
        joined,
        [
            "tensor::par::SharedMut",
            "kernel::combine",
            "kernel::layout::transpose"
        ]
    );
    assert!(layer("tensor") > layer("kernel"), "that import is upward");
    assert!(breaks_map("kernel", "tensor", &layer).is_some(), "upward");
    // within a layer only the listed pairs pass: the coders never see the codec, the
    // meshes never the upscaler
    assert!(
        breaks_map("entropy", "codec", &layer).is_some(),
        "entropy → codec"
    );
    assert!(
        breaks_map("mesh", "upscale", &layer).is_some(),
        "mesh → upscale"
    );
    assert!(
        breaks_map("codec", "entropy", &layer).is_none(),
        "codec → entropy"
    );
    assert!(breaks_map("codec", "io", &layer).is_none(), "downward");
    assert!(breaks_map("codec", "nowhere", &layer).is_some(), "unmapped");
    let mut e: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    e.entry("a".into()).or_default().insert("b".into());
    e.entry("b".into()).or_default().insert("c".into());
    assert_eq!(cycle(&e), None);
    e.entry("c".into()).or_default().insert("a".into());
    assert_eq!(cycle(&e).map(|c| c.len()), Some(4));
    assert!(nested("kernel::x86::avx2", "kernel") && !nested("kernel", "kernel_x"));
}
