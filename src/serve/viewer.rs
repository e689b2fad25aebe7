//! The pages: `/` lists the served files, `/viewer.html?id=…` opens one in
//! OpenSeadragon (vendored from the npm registry's `openseadragon` package, minified
//! build and licence under `src/serve/assets/`, embedded in the binary).

use super::ident;
use std::path::Path;

/// OpenSeadragon's minified build.
const OSD_JS: &[u8] = include_bytes!("assets/openseadragon.min.js");
/// OpenSeadragon's licence (BSD 3-clause).
const OSD_LICENSE: &[u8] = include_bytes!("assets/LICENSE-openseadragon.txt");

/// The most files the index lists, and the deepest folder it looks into.
const MAX_LISTED: usize = 2000;
const MAX_DEPTH: usize = 8;

/// An embedded asset by name: its media type and bytes.
pub fn asset(name: &str) -> Option<(&'static str, &'static [u8])> {
    match name {
        "openseadragon.min.js" => Some(("text/javascript; charset=utf-8", OSD_JS)),
        "LICENSE-openseadragon.txt" => Some(("text/plain; charset=utf-8", OSD_LICENSE)),
        _ => None,
    }
}

/// The viewer page: reads `id` (and optionally `format`) from its query, fetches the
/// image's `info.json` and opens it; `window.viewer` is the OpenSeadragon viewer.
pub const VIEWER: &str = r#"<!doctype html>
<html><head><meta charset="utf-8"><title>mra viewer</title>
<style>html,body{margin:0;height:100%;background:#222;color:#ddd;font:14px sans-serif}
#osd{position:absolute;top:0;left:0;right:0;bottom:0}
#bar{position:absolute;top:4px;left:8px;z-index:10}#bar a{color:#9cf}</style>
<script src="/assets/openseadragon.min.js"></script></head>
<body><div id="osd"></div><div id="bar"><a href="/">files</a> <span id="name"></span></div>
<script>
const q = new URLSearchParams(location.search);
const id = q.get("id") || "";
const format = q.get("format") || "jpg";
document.getElementById("name").textContent = id;
window.viewerReady = false;
fetch("/iiif/3/" + encodeURIComponent(id) + "/info.json")
  .then(r => { if (!r.ok) throw new Error(r.status + " " + r.statusText); return r.json(); })
  .then(info => {
    // the format asked for first (OpenSeadragon takes preferredFormats over tileFormat)
    info.preferredFormats = [format];
    window.viewer = OpenSeadragon({
      id: "osd", tileSources: info, showNavigationControl: false,
      animationTime: 0, blendTime: 0, immediateRender: false,
      // a level is drawn from 0.9 screen pixels per level sample (OpenSeadragon's 0.5
      // would draw the next finer level shrunk by the canvas): at a level's own zoom the
      // screen shows that level's samples one to one
      minPixelRatio: 0.9, maxZoomPixelRatio: 1, minZoomImageRatio: 0.5,
      crossOriginPolicy: "Anonymous",
      imageSmoothingEnabled: false,
    });
    window.viewer.addHandler("open", () => { window.viewerReady = true; });
  })
  .catch(e => { document.getElementById("name").textContent = id + ": " + e.message; });
</script></body></html>
"#;

/// `<`, `>`, `&`, `"` and `'` as HTML entities.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '&' => o.push_str("&amp;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// The `.mra` files under `root` (relative, `/`-separated, sorted), symlinks not
/// followed, at most [`MAX_LISTED`].
pub fn files(root: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![(root.to_path_buf(), 0usize)];
    while let Some((dir, depth)) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in rd.flatten() {
            let Ok(ft) = e.file_type() else { continue };
            let p = e.path();
            if ft.is_dir() && depth < MAX_DEPTH {
                stack.push((p, depth + 1));
            } else if ft.is_file() && p.extension().is_some_and(|x| x == "mra") {
                if let Some(rel) = p.strip_prefix(root).ok().and_then(|r| r.to_str()) {
                    out.push(rel.replace('\\', "/"));
                }
            }
            if out.len() >= MAX_LISTED {
                break;
            }
        }
    }
    out.sort();
    out
}

/// The index page.
pub fn index(root: &Path) -> String {
    let mut rows = String::new();
    for rel in files(root) {
        let what = crate::codec::header_of_file(&root.join(&rel))
            .map(|h| {
                let dims: Vec<String> = h.dims.iter().rev().map(|d| d.to_string()).collect();
                format!(
                    "{} {} × {} channel(s) {}",
                    crate::codec::kind_name(h.kind),
                    dims.join(" × "),
                    h.channels,
                    h.sample_type.name()
                )
            })
            .unwrap_or_else(|e| format!("unreadable: {e}"));
        let id = ident::encode(&rel);
        rows.push_str(&format!(
            "<li><a href=\"/viewer.html?id={id}\">{}</a> — {} · <a href=\"/iiif/3/{id}/info.json\">info.json</a></li>\n",
            escape(&rel),
            escape(&what)
        ));
    }
    if rows.is_empty() {
        rows.push_str("<li>no .mra files</li>");
    }
    format!(
        "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>mra serve</title></head>\n<body style=\"font:14px sans-serif\"><h1>mra serve</h1><ul>\n{rows}</ul>\n<p>IIIF Image API 3.0 under /iiif/3/. Viewer: OpenSeadragon (<a href=\"/assets/LICENSE-openseadragon.txt\">licence</a>).</p></body></html>\n"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_in_names_is_escaped() {
        assert_eq!(escape("<a href='x'>&"), "&lt;a href=&#39;x&#39;&gt;&amp;");
    }

    #[test]
    fn the_assets_are_embedded() {
        assert!(asset("openseadragon.min.js").unwrap().1.len() > 100_000);
        assert!(asset("LICENSE-openseadragon.txt").is_some());
        assert!(asset("../Cargo.toml").is_none());
    }
}
