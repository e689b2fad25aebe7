//! `mra serve` end to end: the server started on 127.0.0.1 with an ephemeral port over
//! files the tests generate, asked over plain HTTP/1.1 (a few lines of std, no client
//! crate): info.json, served pixels against `mra decode --region --level`, ETags, the
//! IIIF level-2 checks of the compliance document, and hostile requests.
#![cfg(feature = "serve")]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

fn mra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mra"))
}

fn run(args: &[&str]) {
    let out = mra().args(args).output().expect("run mra");
    assert!(
        out.status.success(),
        "mra {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `mra generate kind -o dir/out extra…`.
fn generate(d: &Dir, kind: &str, out: &str, extra: &[&str]) {
    run(&[&["generate", kind, "-o", &d.s(out)], extra].concat());
}

/// `mra encode dir/src -o dir/out --quality 60 extra…`.
fn encode(d: &Dir, src: &str, out: &str, extra: &[&str]) {
    run(&[
        &["encode", &d.s(src), "-o", &d.s(out), "--quality", "60"],
        extra,
    ]
    .concat());
}

/// A temporary folder removed on drop.
struct Dir(PathBuf);

impl Dir {
    fn new(name: &str) -> Dir {
        let p = std::env::temp_dir().join(format!("mra-serve-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        Dir(p)
    }
    fn join(&self, s: &str) -> PathBuf {
        self.0.join(s)
    }
    fn s(&self, s: &str) -> String {
        self.join(s).display().to_string()
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A running server, killed on drop.
struct Server {
    child: Child,
    addr: SocketAddr,
}

impl Server {
    fn start(dir: &Path) -> Server {
        Server::start_with(dir, &[])
    }

    fn start_with(dir: &Path, extra: &[&str]) -> Server {
        Server::start_env(dir, extra, &[])
    }

    fn start_env(dir: &Path, extra: &[&str], env: &[(&str, &str)]) -> Server {
        let mut child = mra()
            .args(["serve", &dir.display().to_string(), "--bind", "127.0.0.1:0"])
            .args(extra)
            .env("MRA_MAX_BYTES", "256M")
            .envs(env.iter().copied())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start mra serve");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let addr = line
            .split("http://")
            .nth(1)
            .and_then(|t| t.trim().trim_end_matches('/').parse().ok())
            .unwrap_or_else(|| panic!("no address in {line:?}"));
        Server { child, addr }
    }

    /// GET `path` (sent as given) with extra header lines.
    fn get_with(&self, path: &str, extra: &str) -> Response {
        let mut s = TcpStream::connect(self.addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
        // a server refusing an over-long request may close before it is all written
        let _ = write!(
            s,
            "GET {path} HTTP/1.1\r\nHost: {}\r\nConnection: close\r\n{extra}\r\n",
            self.addr
        );
        let mut raw = Vec::new();
        let _ = s.read_to_end(&mut raw);
        Response::parse(&raw)
    }

    /// GET `path`, which must answer 200 (the body shown otherwise).
    fn get_ok(&self, path: &str) -> Response {
        let r = self.get(path);
        assert_eq!(
            r.status,
            200,
            "{path}: {}",
            String::from_utf8_lossy(&r.body)
        );
        r
    }

    fn get(&self, path: &str) -> Response {
        self.get_with(path, "")
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

struct Response {
    status: u16,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Response {
    fn parse(raw: &[u8]) -> Response {
        let end = raw
            .windows(4)
            .position(|w| w == b"\r\n\r\n")
            .unwrap_or(raw.len());
        let head = String::from_utf8_lossy(&raw[..end]).to_string();
        let mut lines = head.lines();
        let status = lines
            .next()
            .and_then(|l| l.split(' ').nth(1))
            .and_then(|c| c.parse().ok())
            .unwrap_or(0);
        let headers: Vec<(String, String)> = lines
            .filter_map(|l| l.split_once(':'))
            .map(|(k, v)| (k.trim().to_ascii_lowercase(), v.trim().to_string()))
            .collect();
        let mut body = raw[(end + 4).min(raw.len())..].to_vec();
        let chunked = headers
            .iter()
            .any(|(k, v)| k == "transfer-encoding" && v.contains("chunked"));
        if chunked {
            body = unchunk(&body);
        }
        Response {
            status,
            headers,
            body,
        }
    }

    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    fn json(&self) -> serde_json::Value {
        serde_json::from_slice(&self.body).expect("a JSON body")
    }

    fn image(&self) -> image::DynamicImage {
        image::load_from_memory(&self.body).expect("an image body")
    }
}

fn unchunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let Some(nl) = b.windows(2).position(|w| w == b"\r\n") else {
            return out;
        };
        let n = usize::from_str_radix(String::from_utf8_lossy(&b[..nl]).trim(), 16).unwrap_or(0);
        if n == 0 {
            return out;
        }
        out.extend_from_slice(&b[nl + 2..nl + 2 + n]);
        b = &b[nl + 2 + n + 2..];
    }
}

/// A folder with a 1024² zone plate coded whole and tiled (256² tiles), a heightmap and
/// a volume.
fn corpus(name: &str) -> Dir {
    let d = Dir::new(name);
    generate(&d, "zone-plate", "z.png", &["--size", "1024"]);
    encode(&d, "z.png", "z.mra", &[]);
    std::fs::create_dir_all(d.join("sub dir")).unwrap();
    encode(&d, "z.png", "sub dir/tiled.mra", &["--tile", "256"]);
    // a float TIFF of one channel reads as a heightmap
    generate(&d, "terrain", "t.tif", &["--size", "257", "--dtype", "f32"]);
    encode(&d, "t.tif", "t.mra", &[]);
    generate(&d, "phantom", "v.nrrd", &["--size", "64"]);
    encode(&d, "v.nrrd", "v.mra", &[]);
    d
}

#[test]
fn info_json_has_the_level_2_fields_and_the_files_levels() {
    let d = corpus("info");
    let s = Server::start(&d.0);
    let r = s.get("/iiif/3/z.mra/info.json");
    assert_eq!(r.status, 200);
    assert_eq!(r.header("access-control-allow-origin"), Some("*"));
    assert!(r.header("etag").is_some());
    let j = r.json();
    assert_eq!(j["@context"], "http://iiif.io/api/image/3/context.json");
    assert_eq!(j["type"], "ImageService3");
    assert_eq!(j["protocol"], "http://iiif.io/api/image");
    assert_eq!(j["profile"], "level2");
    assert_eq!(
        (j["width"].as_u64(), j["height"].as_u64()),
        (Some(1024), Some(1024))
    );
    assert_eq!(j["id"], format!("http://{}/iiif/3/z.mra", s.addr));
    let sizes = j["sizes"].as_array().unwrap();
    assert!(sizes.len() >= 4, "{sizes:?}");
    assert_eq!(sizes.last().unwrap()["width"], 1024);
    assert_eq!(sizes[sizes.len() - 2]["width"], 512);
    let t = &j["tiles"][0];
    assert_eq!(t["width"], 256);
    let f = t["scaleFactors"].as_array().unwrap();
    assert_eq!(f[0], 1);
    assert_eq!(f[1], 2);
    // JSON-LD when asked for it
    let r = s.get_with("/iiif/3/z.mra/info.json", "Accept: application/ld+json\r\n");
    assert!(r
        .header("content-type")
        .unwrap()
        .starts_with("application/ld+json"));
    // the base URI redirects to info.json; a percent-encoded path in a subfolder
    let r = s.get("/iiif/3/z.mra");
    assert_eq!(r.status, 303);
    assert_eq!(r.header("location"), Some("/iiif/3/z.mra/info.json"));
    assert_eq!(s.get("/iiif/3/sub%20dir%2Ftiled.mra/info.json").status, 200);
}

/// The samples of a PNG as 8-bit gray.
fn gray(img: &image::DynamicImage) -> (u32, u32, Vec<u8>) {
    let g = img.to_luma8();
    (g.width(), g.height(), g.into_raw())
}

#[test]
fn a_served_region_equals_mra_decode_of_the_same_window() {
    let d = corpus("pixels");
    // the same indices cut into code-blocks (format 3.0): each request decodes only its
    // window, which must be the window of the whole decode of z.mra
    encode(&d, "z.png", "b.mra", &["--blocks"]);
    // the untiled file's levels kept whole, the tiled file's tiles one by one; and with a
    // 1 MiB cache (256 KiB a level) the untiled file's level 0 decoded for each request
    let whole = Server::start(&d.0);
    let by_tile = Server::start_with(&d.0, &["--cache", "1M"]);
    // the 3.0 file's levels cut into 64² patches: windows assembled from many decodes
    // (the first request of a patch decodes its own part of it, the next the patch: each
    // window is asked twice, as default and as gray, which a gray image answers alike)
    let patches = Server::start_env(&d.0, &[], &[("MRA_SERVE_PATCH", "64")]);
    // and with its levels decoded whole before serving: every window cut from them
    let warm = Server::start_with(&d.0, &["--warm"]);
    for (s, id, file) in [
        (&patches, "b.mra", "z.mra"),
        (&warm, "b.mra", "z.mra"),
        (&whole, "z.mra", "z.mra"),
        (&whole, "sub%20dir%2Ftiled.mra", "sub dir/tiled.mra"),
        (&by_tile, "sub%20dir%2Ftiled.mra", "sub dir/tiled.mra"),
        (&by_tile, "z.mra", "z.mra"),
        (&whole, "b.mra", "z.mra"),
    ] {
        // (x, y, w, h, level): aligned to 2^level, output w/2^level wide
        for (x, y, w, h, k) in [
            (0u32, 0u32, 1024u32, 1024u32, 2u32),
            (256, 512, 256, 256, 0),
            (128, 64, 512, 256, 1),
            (512, 512, 512, 512, 2),
            (0, 0, 1024, 1024, 3),
            (200, 328, 400, 300, 0),
            // more output pixels than a cut rendered on the connection's thread
            // (INLINE_CUT): with --warm, cut on the blocking pool
            (0, 0, 1024, 1024, 0),
        ] {
            let ow = w >> k;
            let path = format!("/iiif/3/{id}/{x},{y},{w},{h}/{ow},/0/default.png");
            let r = s.get_ok(&path);
            assert_eq!(r.header("content-type"), Some("image/png"));
            if std::ptr::eq(s, &warm) {
                // every level held whole: a cut, small or large, wherever it is rendered
                let timing = r.header("server-timing").unwrap_or_default();
                assert!(
                    timing.starts_with("render;desc=\"level level="),
                    "{path}: {timing}"
                );
            }
            let served = gray(&r.image());
            let again = std::ptr::eq(s, &patches).then(|| {
                let r = s.get_ok(&path.replace("default.png", "gray.png"));
                (
                    gray(&r.image()),
                    r.header("server-timing").map(str::to_string),
                )
            });
            let out = d.s(&format!("ref-{k}-{x}-{y}-{}.png", s.addr.port()));
            run(&[
                "decode",
                &d.s(file),
                "-o",
                &out,
                "--level",
                &k.to_string(),
                "--region",
                &format!("{x}:{},{y}:{}", x + w, y + h),
            ]);
            let want = gray(&image::open(&out).unwrap());
            assert_eq!((served.0, served.1), (want.0, want.1), "{path}");
            assert!(served.2 == want.2, "{path}: pixels differ from mra decode");
            if let Some((again, timing)) = again {
                assert!(
                    again.2 == want.2,
                    "{path} as gray: pixels differ from mra decode"
                );
                let timing = timing.unwrap_or_default();
                assert!(timing.contains("render;"), "{path} as gray: {timing}");
            }
        }
    }
}

/// The IIIF region `x,y,w,h` is columns `x..x+w` and rows `y..y+h`: on a 300 × 200 tiled
/// image the served window equals the library's decode of the box `[y..y+h, x..x+w]`
/// (slowest axis first), a window that would not fit the image with its axes swapped.
#[test]
fn a_served_window_of_a_non_square_image_is_the_library_box_rows_first() {
    let d = Dir::new("serve-axes");
    generate(&d, "zone-plate", "w.png", &["--size", "300x200"]);
    encode(&d, "w.png", "w.mra", &["--tile", "64"]);
    let s = Server::start(&d.0);
    let (x, y, w, h) = (200usize, 20usize, 90usize, 150usize);
    let path = format!("/iiif/3/w.mra/{x},{y},{w},{h}/{w},/0/default.png");
    let r = s.get_ok(&path);
    let served = gray(&r.image());
    let want = mra::codec::decode_file(
        &d.join("w.mra"),
        &mra::codec::DecodeOptions {
            region: Some(vec![y..y + h, x..x + w]),
            ..Default::default()
        },
    )
    .unwrap()
    .raster;
    assert_eq!(want.dims, vec![h, w]);
    assert_eq!((served.0 as usize, served.1 as usize), (w, h), "{path}");
    let mra::io::Samples::U8(px) = want.samples else {
        panic!("expected u8 samples")
    };
    assert!(
        served.2 == px,
        "{path}: pixels differ from the library's box"
    );
}

/// A file replaced on disk is picked up: a new `ETag` and the new file's pixels, though
/// the old file's decoded samples and encoded answers are held (a one-tile file, a 3.0
/// file of code-blocks).
#[test]
fn the_etag_changes_when_the_file_is_replaced_and_a_match_is_304() {
    the_etag_changes_with(&[], "etag");
    the_etag_changes_with(&["--blocks"], "etag-blocks");
}

fn the_etag_changes_with(blocks: &[&str], name: &str) {
    let d = corpus(name);
    encode(&d, "z.png", "z.mra", blocks);
    let s = Server::start(&d.0);
    let path = "/iiif/3/z.mra/0,0,256,256/256,/0/default.png";
    let a = s.get(path);
    // asked again: the answer kept, the same bytes
    assert_eq!(s.get(path).body, a.body);
    let tag = a.header("etag").unwrap().to_string();
    assert_eq!(a.header("cache-control"), Some("public, max-age=60"));
    let same = s.get_with(path, &format!("If-None-Match: {tag}\r\n"));
    assert_eq!(same.status, 304);
    // replaced (by rename, as tools write files) with another coding of the image
    run(&[
        "encode",
        &d.s("z.png"),
        "-o",
        &d.s("z2.mra"),
        "--quality",
        "20",
    ]
    .iter()
    .chain(blocks)
    .copied()
    .collect::<Vec<_>>());
    std::fs::rename(d.join("z2.mra"), d.join("z.mra")).unwrap();
    let b = s.get_with(path, &format!("If-None-Match: {tag}\r\n"));
    assert_eq!(b.status, 200);
    assert_ne!(b.header("etag").unwrap(), tag);
    assert_ne!(
        gray(&a.image()).2,
        gray(&b.image()).2,
        "the new file's pixels"
    );
    let out = d.s("new.png");
    run(&[
        "decode",
        &d.s("z.mra"),
        "-o",
        &out,
        "--region",
        "0:256,0:256",
    ]);
    assert!(
        gray(&b.image()).2 == gray(&image::open(&out).unwrap()).2,
        "the answer is the new file's decode"
    );
}

#[test]
fn the_level_2_features_answer_with_their_sizes() {
    let d = corpus("level2");
    let s = Server::start(&d.0);
    let dims = |p: &str| {
        let r = s.get(&format!("/iiif/3/z.mra/{p}"));
        assert_eq!(r.status, 200, "{p}: {}", String::from_utf8_lossy(&r.body));
        let i = r.image();
        (i.width(), i.height())
    };
    assert_eq!(dims("full/max/0/default.jpg"), (1024, 1024));
    assert_eq!(dims("square/100,/0/default.jpg"), (100, 100));
    assert_eq!(dims("pct:10,10,50,25/max/0/default.png"), (512, 256));
    assert_eq!(dims("0,0,600,300/,150/0/default.png"), (300, 150));
    assert_eq!(dims("0,0,600,300/pct:50/0/default.png"), (300, 150));
    assert_eq!(dims("0,0,600,300/100,100/0/default.png"), (100, 100));
    assert_eq!(dims("0,0,600,300/!100,100/0/default.png"), (100, 50));
    assert_eq!(dims("0,0,600,300/300,/90/default.png"), (150, 300));
    assert_eq!(dims("0,0,600,300/300,/!180/gray.png"), (300, 150));
    assert_eq!(dims("0,0,600,300/300,/270/color.png"), (150, 300));
    assert_eq!(dims("0,0,600,300/300,/0/bitonal.png"), (300, 150));
    // color is three channels, gray one; 90° turns the picture
    let c = s.get("/iiif/3/z.mra/0,0,64,32/max/0/color.png").image();
    assert_eq!(c.color().channel_count(), 3);
    let a = gray(&s.get("/iiif/3/z.mra/0,0,64,32/max/0/gray.png").image());
    let b = gray(&s.get("/iiif/3/z.mra/0,0,64,32/max/90/gray.png").image());
    assert_eq!((b.0, b.1), (32, 64));
    // output (x, y) of the turn is input (y, 31 − x)... i.e. input (row r, col q) lands
    // at row q, column 31 − r
    for (r, q) in [(0usize, 0usize), (5, 40), (31, 63)] {
        assert_eq!(b.2[q * 32 + (31 - r)], a.2[r * 64 + q]);
    }
}

#[test]
fn heightmaps_are_hillshaded_and_volumes_sliced() {
    let d = corpus("kinds");
    let s = Server::start(&d.0);
    let r = s.get("/iiif/3/t.mra/full/max/0/default.png");
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let (w, h, px) = gray(&r.image());
    assert_eq!((w, h), (257, 257));
    let distinct: std::collections::BTreeSet<u8> = px.iter().copied().collect();
    assert!(distinct.len() > 20, "a shaded relief, not flat");
    // 16-bit windowing: a window over the data's range differs from the default
    let v = s.get("/iiif/3/v.mra;z=32/info.json").json();
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(64), Some(64))
    );
    let a = s.get("/iiif/3/v.mra;z=32/full/max/0/default.png");
    assert_eq!(a.status, 200);
    let b = s.get("/iiif/3/v.mra;z=32/full/max/0/default.png?window=0,100");
    assert_eq!(b.status, 200);
    assert_ne!(gray(&a.image()).2, gray(&b.image()).2);
    assert_eq!(
        s.get("/iiif/3/v.mra;y=10/full/max/0/default.png").status,
        200
    );
    assert_eq!(s.get("/iiif/3/v.mra;z=64/info.json").status, 400);
    assert_eq!(
        s.get("/iiif/3/v.mra;z=1/full/max/0/default.png?window=5,1")
            .status,
        400
    );
    assert_eq!(s.get("/iiif/3/z.mra;z=1/info.json").status, 400);
}

#[test]
fn hostile_requests_are_refused_with_4xx_and_the_server_goes_on() {
    let d = corpus("hostile");
    // a file outside the served folder, and a symlink to it from inside
    let outside = Dir::new("outside");
    std::fs::copy(d.join("z.mra"), outside.join("secret.mra")).unwrap();
    let served = d.join("served");
    std::fs::create_dir_all(&served).unwrap();
    std::fs::copy(d.join("z.mra"), served.join("z.mra")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(outside.join("secret.mra"), served.join("link.mra")).unwrap();
    let s = Server::start(&served);
    let long = "9".repeat(3000);
    let huge = "a".repeat(20_000);
    let bad: Vec<String> = vec![
        "/iiif/3/../outside/secret.mra/info.json".into(),
        "/iiif/3/%2e%2e%2fsecret.mra/info.json".into(),
        "/iiif/3/..%2fsecret.mra/info.json".into(),
        "/iiif/3/..%2F..%2F..%2Fetc%2Fpasswd/info.json".into(),
        format!("/iiif/3/{}/info.json", outside.join("secret.mra").display()),
        format!(
            "/iiif/3/%2F{}/info.json",
            outside.join("secret.mra").display()
        ),
        "/iiif/3/link.mra/info.json".into(),
        "/iiif/3/link.mra/full/max/0/default.jpg".into(),
        "/iiif/3/nothere.mra/info.json".into(),
        "/iiif/3/z.mra/full/99999,/0/default.jpg".into(),
        "/iiif/3/z.mra/full/1025,/0/default.jpg".into(),
        "/iiif/3/z.mra/full/^2048,/0/default.jpg".into(),
        "/iiif/3/z.mra/full/99999999999999999999999,/0/default.jpg".into(),
        "/iiif/3/z.mra/-10,0,100,100/max/0/default.jpg".into(),
        "/iiif/3/z.mra/0,0,0,100/max/0/default.jpg".into(),
        "/iiif/3/z.mra/0,0,100,0/max/0/default.jpg".into(),
        "/iiif/3/z.mra/5000,0,100,100/max/0/default.jpg".into(),
        "/iiif/3/z.mra/a,b,c,d/max/0/default.jpg".into(),
        "/iiif/3/z.mra/full/max/45/default.jpg".into(),
        "/iiif/3/z.mra/full/max/0/default.gif".into(),
        "/iiif/3/z.mra/full/max/0/sepia.jpg".into(),
        "/iiif/3/z.mra/full/0,/0/default.jpg".into(),
        "/iiif/3/z.mra/full/pct:0/0/default.jpg".into(),
        format!("/iiif/3/z.mra/{long},0,1,1/max/0/default.jpg"),
        format!("/iiif/3/z.mra/full/max/0/default.jpg?{long}{long}"),
        "/iiif/3/%ff%fe.mra/info.json".into(),
        "/iiif/3/z.mra;q=1/info.json".into(),
        "/nothing".into(),
        "/assets/..%2f..%2fCargo.toml".into(),
    ];
    for (i, p) in bad.iter().enumerate() {
        let r = s.get(p);
        let shown: String = p.chars().take(80).collect();
        assert!(
            (400..500).contains(&r.status),
            "{shown}: {} {}",
            r.status,
            String::from_utf8_lossy(&r.body)
        );
        if i % 8 == 0 {
            assert_eq!(
                s.get("/iiif/3/z.mra/0,0,256,256/256,/0/default.jpg").status,
                200
            );
        }
    }
    // a secret's bytes never come back, and a good request still works
    assert_eq!(
        s.get("/iiif/3/z.mra/0,0,256,256/256,/0/default.jpg").status,
        200
    );
    // a request line too long for the server's buffer is refused (431) or the connection
    // closed (the client may see the reset before the answer), never answered 2xx
    for p in [
        format!("/iiif/3/{huge}/info.json"),
        format!("/iiif/3/{}/info.json", "b".repeat(70_000)),
    ] {
        let r = s.get(&p);
        assert!(
            r.status == 0 || (400..500).contains(&r.status),
            "{}",
            r.status
        );
    }
    assert_eq!(s.get("/iiif/3/z.mra/info.json").status, 200);
}

#[test]
fn the_viewer_page_lists_the_files_and_embeds_openseadragon() {
    let d = corpus("viewer");
    let s = Server::start(&d.0);
    let r = s.get("/");
    assert_eq!(r.status, 200);
    let page = String::from_utf8_lossy(&r.body);
    assert!(page.contains("viewer.html?id=z.mra"), "{page}");
    assert!(
        page.contains("viewer.html?id=sub%20dir%2Ftiled.mra"),
        "{page}"
    );
    let v = s.get("/viewer.html");
    assert!(String::from_utf8_lossy(&v.body).contains("OpenSeadragon("));
    let js = s.get("/assets/openseadragon.min.js");
    assert_eq!(js.status, 200);
    assert!(js.body.len() > 100_000);
    assert_eq!(s.get("/assets/LICENSE-openseadragon.txt").status, 200);
}
