//! The HTTP side: axum routes on tokio, and the limits that keep one client from holding
//! the server.
//!
//! ```text
//! connections   at most MAX_CONNECTIONS open; a further one is closed at once
//! headers       read within HEADER_TIMEOUT (slowloris), at most 16 KiB (431 past that)
//! connection    closed after CONNECTION_LIFETIME whatever it does
//! requests      at most MAX_IN_FLIGHT handled at once, the others wait; an answer
//!               not ready within REQUEST_TIMEOUT is 408
//! decoding      at most `workers` requests decode at once, on blocking threads; a cut
//!               from a level held whole is rendered on the connection's thread
//! URL           at most MAX_URL bytes (414)
//! ```

use super::cache::{AnswerCache, AnswerKey, Key, LevelCache, OpenedCache};
use super::ident::{self, IdentError};
use super::iiif::ImageRequest;
use super::source::{self, OpenedFile, Source};
use super::{info, render, viewer, Config, ServeError};
use crate::limits::Limits;
use axum::body::Body;
use axum::extract::State as AxState;
use axum::http::{header, HeaderMap, HeaderName, HeaderValue, Method, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::Semaphore;

pub const MAX_CONNECTIONS: usize = 512;
pub const MAX_IN_FLIGHT: usize = 64;
pub const HEADER_TIMEOUT: Duration = Duration::from_secs(10);
pub const REQUEST_TIMEOUT: Duration = Duration::from_secs(30);
pub const CONNECTION_LIFETIME: Duration = Duration::from_secs(300);
pub const MAX_URL: usize = 4096;
/// The largest cut from a level held whole rendered on the connection's thread, in
/// output pixels (512², two viewer tiles of 256² a side; its window is at most twice
/// as wide and high): larger ones go to the blocking pool.
pub const INLINE_CUT: u64 = 512 * 512;
/// How long a client may keep an answer before asking again (with its `ETag`).
pub const CACHE_CONTROL: &str = "public, max-age=60";

/// What every request sees.
pub struct State {
    pub root: PathBuf,
    pub addr: SocketAddr,
    pub cache: LevelCache,
    /// Encoded answers of image requests.
    pub answers: AnswerCache,
    /// One-piece 3.0 files parsed once.
    pub opened: OpenedCache,
    /// Held while a file's levels are decoded in the background (one file at a time).
    pub warming: std::sync::Mutex<()>,
    pub limits: Limits,
    pub work: Arc<Semaphore>,
}

impl State {
    /// The cache budget (`--cache`, at most `MRA_MAX_BYTES`) is shared: 3/4 for decoded
    /// samples, 1/8 for encoded answers, 1/8 for parsed files.
    pub fn new(root: PathBuf, addr: SocketAddr, c: &Config) -> Arc<State> {
        let budget = c.cache_bytes.min(c.limits.max_bytes);
        let levels = budget - budget / 4;
        Arc::new(State {
            root,
            addr,
            cache: LevelCache::new(levels),
            answers: AnswerCache::new(budget / 8),
            opened: OpenedCache::new(budget / 8),
            warming: std::sync::Mutex::new(()),
            limits: c.limits,
            work: Arc::new(Semaphore::new(c.workers.max(1))),
        })
    }
}

/// The routes with their layers (CORS outermost, then the timeout, then the bound on
/// requests in flight).
pub fn router(state: Arc<State>) -> Router {
    use tower_http::cors::{Any, CorsLayer};
    let cors = CorsLayer::new()
        .allow_origin(Any)
        .allow_methods([Method::GET, Method::HEAD, Method::OPTIONS])
        .expose_headers([header::ETAG, header::LINK]);
    Router::new()
        .route("/", get(index))
        .route(
            "/viewer.html",
            get(|| async { html(viewer::VIEWER.to_string()) }),
        )
        .route("/assets/{name}", get(asset))
        .route("/iiif/3/{*rest}", get(iiif))
        .fallback(|| async { plain(StatusCode::NOT_FOUND, "not found") })
        .with_state(state)
        .layer(tower::limit::ConcurrencyLimitLayer::new(MAX_IN_FLIGHT))
        .layer(tower_http::timeout::TimeoutLayer::with_status_code(
            StatusCode::REQUEST_TIMEOUT,
            REQUEST_TIMEOUT,
        ))
        .layer(cors)
}

/// Accept connections until the listener fails for good.
pub async fn run(listener: tokio::net::TcpListener, state: Arc<State>) -> std::io::Result<()> {
    use hyper_util::rt::{TokioIo, TokioTimer};
    use hyper_util::service::TowerToHyperService;
    let app = router(state);
    let open = Arc::new(Semaphore::new(MAX_CONNECTIONS));
    loop {
        let stream = match listener.accept().await {
            Ok((s, _)) => s,
            Err(_) => {
                // out of descriptors or a connection reset before accept: wait, go on
                tokio::time::sleep(Duration::from_millis(50)).await;
                continue;
            }
        };
        let Ok(permit) = open.clone().try_acquire_owned() else {
            drop(stream);
            continue;
        };
        // an answer goes out as soon as it is written, not held for the next one's bytes
        let _ = stream.set_nodelay(true);
        let svc = TowerToHyperService::new(app.clone());
        tokio::spawn(async move {
            let conn = hyper::server::conn::http1::Builder::new()
                .timer(TokioTimer::new())
                .header_read_timeout(HEADER_TIMEOUT)
                .max_buf_size(16 * 1024)
                .serve_connection(TokioIo::new(stream), svc);
            let _ = tokio::time::timeout(CONNECTION_LIFETIME, conn).await;
            drop(permit);
        });
    }
}

fn plain(status: StatusCode, msg: &str) -> Response {
    (
        status,
        [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
        format!("{msg}\n"),
    )
        .into_response()
}

fn html(body: String) -> Response {
    ([(header::CONTENT_TYPE, "text/html; charset=utf-8")], body).into_response()
}

fn error_response(e: &ServeError) -> Response {
    let status = match e {
        ServeError::Bad(_) | ServeError::Limits(_) => StatusCode::BAD_REQUEST,
        ServeError::NotFound => StatusCode::NOT_FOUND,
        ServeError::File(_) => StatusCode::INTERNAL_SERVER_ERROR,
    };
    plain(status, &one_line(&e.to_string()))
}

/// A message as one printable line of at most 300 characters.
fn one_line(m: &str) -> String {
    m.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .take(300)
        .collect()
}

async fn asset(axum::extract::Path(name): axum::extract::Path<String>) -> Response {
    match viewer::asset(&name) {
        Some((mime, bytes)) => (
            [
                (header::CONTENT_TYPE, mime),
                (header::CACHE_CONTROL, "public, max-age=86400"),
            ],
            bytes,
        )
            .into_response(),
        None => plain(StatusCode::NOT_FOUND, "not found"),
    }
}

async fn index(AxState(st): AxState<Arc<State>>) -> Response {
    let root = st.root.clone();
    match tokio::task::spawn_blocking(move || viewer::index(&root)).await {
        Ok(page) => html(page),
        Err(_) => plain(StatusCode::INTERNAL_SERVER_ERROR, "listing failed"),
    }
}

/// The base URI of an identifier: the request's `Host` when it is a plain host name
/// or address, else the address bound.
fn base_uri(st: &State, headers: &HeaderMap, id: &str) -> String {
    let host = headers
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .filter(|h| {
            !h.is_empty()
                && h.len() <= 255
                && h.bytes()
                    .all(|b| b.is_ascii_alphanumeric() || b".-:[]".contains(&b))
        })
        .map(str::to_string)
        .unwrap_or_else(|| st.addr.to_string());
    format!("http://{host}/iiif/3/{id}")
}

/// The `?window=lo,hi` extension: the sample values shown as 0 and 255.
fn window_param(uri: &Uri) -> Result<Option<(f64, f64)>, ServeError> {
    let Some(q) = uri.query() else {
        return Ok(None);
    };
    for kv in q.split('&') {
        let Some(v) = kv.strip_prefix("window=") else {
            continue;
        };
        const E: &str = "window=lo,hi with finite numbers lo < hi";
        let v = percent_encoding::percent_decode_str(v).decode_utf8_lossy();
        let mut it = v.split(',').map(|t| t.trim().parse::<f64>());
        return match (it.next(), it.next(), it.next()) {
            (Some(Ok(lo)), Some(Ok(hi)), None) if lo.is_finite() && hi.is_finite() && lo < hi => {
                Ok(Some((lo, hi)))
            }
            _ => Err(ServeError::bad("window", &v, E)),
        };
    }
    Ok(None)
}

/// A one-piece 3.0 file parsed once per version ([`crate::codec::Opened`], kept in the
/// state) and set in `src`; on the first parse of a version, with `background`, its
/// levels decoded in the background ([`Source::warm`]).
fn parse_once(st: &Arc<State>, src: &mut Source, background: bool) -> Result<(), ServeError> {
    if !src.parses_once() {
        return Ok(());
    }
    let k = Key {
        path: src.path.clone(),
        len: src.len,
        mtime: src.mtime,
        level: 0,
        tile: Vec::new(),
    };
    let o = st
        .opened
        .get_or_decode(k, src.len, || {
            let o = Arc::new(crate::codec::Opened::open(&src.path)?);
            if background {
                let mut w = src.clone();
                w.opened = Some(OpenedFile(o.clone()));
                let st = st.clone();
                let _ = std::thread::Builder::new()
                    .name("mra-serve-warm".into())
                    .spawn(move || {
                        let _one = st.warming.lock();
                        // on one thread of its own, so that it takes at most one
                        // core from the requests
                        match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
                            Ok(pool) => pool.install(|| w.warm(&st.cache, &st.limits)),
                            Err(_) => w.warm(&st.cache, &st.limits),
                        }
                    });
            }
            Ok(o)
        })
        .map_err(ServeError::File)?;
    src.opened = Some(OpenedFile(o));
    Ok(())
}

/// `--warm`: every one-piece 3.0 file under the root parsed and its levels that the
/// cache keeps decoded ([`Source::warm`]), before the first request is taken.
pub fn warm_all(st: &Arc<State>) {
    for rel in viewer::files(&st.root) {
        let Ok(mut src) = Source::open(&st.root.join(&rel), None) else {
            continue;
        };
        if parse_once(st, &mut src, false).is_ok() {
            src.warm(&st.cache, &st.limits);
        }
    }
}

/// An answer: status, `ETag`, content type, body.
type Answer = (StatusCode, String, Option<&'static str>, Body);

/// The first step of an IIIF request, on the connection's thread: the file located and
/// its header read, then a 304, info.json, an answer kept, or (no decode needed, so no
/// decode permit) a cut from a level held whole rendered at once; a request that decodes
/// is left as [`Step::Render`] for the blocking pool. A cut of at most [`INLINE_CUT`]
/// output pixels is a copy of its window, a resampling and one JPEG or PNG encode
/// (about half a millisecond for a viewer's 256² tile), less than the two hand-overs
/// between threads it would otherwise cost.
#[allow(clippy::too_many_arguments)]
fn first_step(
    st: &Arc<State>,
    ident: ident::Ident,
    req: Option<ImageRequest>,
    request: String,
    headers: &HeaderMap,
    base: &str,
    window: Option<(f64, f64)>,
    t0: std::time::Instant,
) -> Result<Step, ServeError> {
    let path = ident::locate(&st.root, &ident).map_err(|_| ServeError::NotFound)?;
    let src = Source::open(&path, ident.slice)?;
    let etag = src.etag();
    if headers
        .get(header::IF_NONE_MATCH)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.split(',').any(|t| t.trim() == etag || t.trim() == "*"))
    {
        return Ok(Step::Done((
            StatusCode::NOT_MODIFIED,
            etag,
            None,
            Vec::new().into(),
        )));
    }
    let caps = info::caps(&src, st.limits.max_bytes);
    let Some(req) = req else {
        let doc = info::info_json(&src, base, &caps);
        let ld = headers
            .get(header::ACCEPT)
            .and_then(|v| v.to_str().ok())
            .is_some_and(|a| a.contains("application/ld+json"));
        let mime = if ld {
            "application/ld+json;profile=\"http://iiif.io/api/image/3/context.json\""
        } else {
            "application/json"
        };
        let body = serde_json::to_vec_pretty(&doc).unwrap_or_default();
        return Ok(Step::Done((StatusCode::OK, etag, Some(mime), body.into())));
    };
    let key = AnswerKey {
        path: src.path.clone(),
        len: src.len,
        mtime: src.mtime,
        request,
    };
    let mime = Some(req.format.mime());
    if let Some(body) = st.answers.get(&key) {
        return Ok(Step::Done((StatusCode::OK, etag, mime, body.into())));
    }
    // a cut from a level held whole needs no decode, so no decode permit: it is not
    // queued behind decodes; a small one is rendered here
    let (w, h) = src.size();
    let (cut, small) = match req.resolve(w, h, &caps) {
        Ok(r) => (
            src.level_held(&st.cache, render::choose_level(&src, &r)),
            r.out_w.saturating_mul(r.out_h) <= INLINE_CUT,
        ),
        Err(_) => (false, false),
    };
    let job = Box::new((src, req, caps, key));
    if !(cut && small) {
        return Ok(Step::Render(job, !cut));
    }
    let open = t0.elapsed();
    let (answer, trace) = render_job(st, *job, window, None)?;
    Ok(Step::Rendered(answer, trace, open))
}

/// Where the first step of an image request leaves it.
enum Step {
    Done(Answer),
    /// A cut from a level held whole, rendered at once on the connection's thread: the
    /// answer, what the render did, the time until the render began.
    Rendered(Answer, render::Trace, Duration),
    /// Rendered on the blocking pool: a decode needed (`true`: holding a decode permit),
    /// or a cut of more than [`INLINE_CUT`] output pixels.
    Render(Box<Job>, bool),
}

/// What a render needs: the file, the request, its limits, the key its answer is kept by.
type Job = (Source, ImageRequest, super::iiif::Caps, AnswerKey);

/// Render `job` holding a decode `permit` (none for a cut from a level held whole), and
/// keep the answer.
fn render_job(
    st: &Arc<State>,
    job: Job,
    window: Option<(f64, f64)>,
    permit: Option<tokio::sync::OwnedSemaphorePermit>,
) -> Result<(Answer, render::Trace), ServeError> {
    let _permit = permit;
    let (mut src, req, caps, key) = job;
    parse_once(st, &mut src, true)?;
    let etag = src.etag();
    let (w, h) = src.size();
    let r = req.resolve(w, h, &caps)?;
    let mut trace = render::Trace::default();
    let body = axum::body::Bytes::from(render::render(
        &src, &st.cache, &st.limits, &req, &r, window, &mut trace,
    )?);
    st.answers.put(key, body.len() as u64, body.clone());
    Ok((
        (
            StatusCode::OK,
            etag,
            Some(req.format.mime()),
            Body::from(body),
        ),
        trace,
    ))
}

/// The `Server-Timing` header of an image answer: what it did (`kept`, or `render` with
/// the level read, where the window came from and whether it was resampled) and, in
/// milliseconds, the file's version and kept answers looked up (`open`), the wait for a
/// decode permit (`queue`), the window's values (`window`, decodes included), resampling
/// (`resample`), encoding (`encode`) and all of it (`total`).
fn server_timing(
    open: Duration,
    render: Option<(Duration, &render::Trace)>,
    total: Duration,
) -> String {
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    match render {
        None => format!("kept, open;dur={:.3}, total;dur={:.3}", ms(open), ms(total)),
        Some((queue, t)) => format!(
            "render;desc=\"{} level={} {}\", open;dur={:.3}, queue;dur={:.3}, \
             window;dur={:.3}, resample;dur={:.3}, encode;dur={:.3}, total;dur={:.3}",
            t.via.name(),
            t.level,
            if t.resampled { "resampled" } else { "exact" },
            ms(open),
            ms(queue),
            ms(t.window),
            ms(t.resample),
            ms(t.encode),
            ms(total)
        ),
    }
}

async fn iiif(AxState(st): AxState<Arc<State>>, uri: Uri, headers: HeaderMap) -> Response {
    let t0 = std::time::Instant::now();
    if uri.path().len() + uri.query().map_or(0, str::len) > MAX_URL {
        return plain(StatusCode::URI_TOO_LONG, "URL too long");
    }
    let rest = uri
        .path()
        .strip_prefix("/iiif/3/")
        .unwrap_or("")
        .to_string();
    let segs: Vec<&str> = rest.split('/').collect();
    let n = segs.len();
    let (id, params): (String, Option<[String; 4]>) = match n {
        _ if segs[n - 1] == "info.json" && n >= 2 => (segs[..n - 1].join("/"), None),
        5.. => (
            segs[..n - 4].join("/"),
            Some([0, 1, 2, 3].map(|i| segs[n - 4 + i].to_string())),
        ),
        _ => {
            // the base URI: to info.json, if it names a file
            let id = rest.trim_end_matches('/');
            return match ident::parse(id) {
                Ok(_) => (
                    StatusCode::SEE_OTHER,
                    [(header::LOCATION, format!("/iiif/3/{id}/info.json"))],
                )
                    .into_response(),
                Err(IdentError::Malformed) => plain(StatusCode::BAD_REQUEST, "bad identifier"),
                Err(IdentError::NotFound) => plain(StatusCode::NOT_FOUND, "no such image"),
            };
        }
    };
    let window = match window_param(&uri) {
        Ok(w) => w,
        Err(e) => return error_response(&e),
    };
    let req = match &params {
        Some([r, s, o, q]) => match ImageRequest::parse(r, s, o, q) {
            Ok(req) => Some(req),
            Err(e) => return error_response(&e.into()),
        },
        None => None,
    };
    let ident = match ident::parse(&id) {
        Ok(i) => i,
        Err(IdentError::Malformed) => return plain(StatusCode::BAD_REQUEST, "bad identifier"),
        Err(IdentError::NotFound) => return plain(StatusCode::NOT_FOUND, "no such image"),
    };
    let req_is_image = req.is_some();
    let base = base_uri(&st, &headers, &id);
    let request = match uri.query() {
        Some(q) => format!("{}?{q}", uri.path()),
        None => uri.path().to_string(),
    };
    if let Some(r) = &req {
        if let Some(resp) = kept_answer(&st, &ident, &request, r, &headers, t0) {
            return resp;
        }
    }
    // on the connection's own thread (no hand-over to another thread): the file's
    // version, a 304, info.json, an answer already encoded, or a cut from a level held
    // whole; only a request that decodes goes to the blocking pool
    let step = first_step(&st, ident, req, request, &headers, &base, window, t0);
    let mut opened = t0.elapsed();
    let mut timing = None;
    let done = match step {
        Ok(Step::Done(d)) => Ok(d),
        Ok(Step::Rendered(answer, trace, open)) => {
            opened = open;
            timing = Some((Duration::ZERO, trace));
            Ok(answer)
        }
        Err(e) => Err(e),
        Ok(Step::Render(job, decodes)) => {
            let permit = if decodes {
                let Ok(permit) = st.work.clone().acquire_owned().await else {
                    return plain(StatusCode::SERVICE_UNAVAILABLE, "shutting down");
                };
                Some(permit)
            } else {
                None
            };
            let queue = t0.elapsed() - opened;
            let st2 = st.clone();
            let job = tokio::task::spawn_blocking(move || render_job(&st2, *job, window, permit));
            match job.await {
                Ok(Ok((answer, trace))) => {
                    timing = Some((queue, trace));
                    Ok(answer)
                }
                Ok(Err(e)) => Err(e),
                Err(_) => return plain(StatusCode::INTERNAL_SERVER_ERROR, "the request failed"),
            }
        }
    };
    let kept = matches!(&done, Ok((StatusCode::OK, ..))) && timing.is_none() && req_is_image;
    match done {
        Ok((status, etag, mime, body)) => {
            let t = (kept || timing.is_some()).then(|| {
                server_timing(opened, timing.as_ref().map(|(q, t)| (*q, t)), t0.elapsed())
            });
            answer(status, &etag, mime, body, t)
        }
        Err(e) => error_response(&e),
    }
}

/// An IIIF answer: its status, body and type, the file version's `ETag`, the caching and
/// profile headers every answer carries, and `Server-Timing` when given.
fn answer(
    status: StatusCode,
    etag: &str,
    mime: Option<&'static str>,
    body: Body,
    timing: Option<String>,
) -> Response {
    let mut resp = Response::new(body);
    *resp.status_mut() = status;
    let h = resp.headers_mut();
    if let Some(m) = mime {
        h.insert(header::CONTENT_TYPE, HeaderValue::from_static(m));
    }
    if let Ok(v) = HeaderValue::from_str(etag) {
        h.insert(header::ETAG, v);
    }
    h.insert(
        header::CACHE_CONTROL,
        HeaderValue::from_static(CACHE_CONTROL),
    );
    h.insert(
        header::LINK,
        HeaderValue::from_static("<http://iiif.io/api/image/3/level2.json>;rel=\"profile\""),
    );
    if let Some(t) = timing.and_then(|t| HeaderValue::from_str(&t).ok()) {
        h.insert(HeaderName::from_static("server-timing"), t);
    }
    resp
}

/// An answer already kept, found on the connection's own thread without the blocking
/// pool: the file located and its length and modification time read (`stat`, the
/// version [`Source::open`] reads), the answer looked up under the same key. `None` sends
/// the request the long way: not kept, a conditional request (its 304 is answered
/// there), or any error.
fn kept_answer(
    st: &State,
    id: &ident::Ident,
    request: &str,
    req: &ImageRequest,
    headers: &HeaderMap,
    t0: std::time::Instant,
) -> Option<Response> {
    if headers.contains_key(header::IF_NONE_MATCH) {
        return None;
    }
    let path = ident::locate(&st.root, id).ok()?;
    let (len, mtime) = source::version(&std::fs::metadata(&path).ok()?);
    let key = AnswerKey {
        path,
        len,
        mtime,
        request: request.to_string(),
    };
    let body = st.answers.get(&key)?;
    let open = t0.elapsed();
    let timing = server_timing(open, None, t0.elapsed());
    Some(answer(
        StatusCode::OK,
        &source::etag(len, mtime),
        Some(req.format.mime()),
        body.into(),
        Some(timing),
    ))
}
