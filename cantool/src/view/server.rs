//! The view's HTTP server (axum on a one-thread tokio runtime): the page (three files built
//! into the binary, so it works offline), the picture as a stream of server-sent events,
//! and the page's two requests, the replay's controls and the sender panel's
//! `ThresholdConfig`.
//!
//! | request | answer |
//! |---|---|
//! | `GET /`, `/view.js`, `/view.css` | the page |
//! | `GET /state` | one [`Snapshot`] as JSON |
//! | `GET /events` | a snapshot every [`EVENT_PERIOD`] as `text/event-stream` |
//! | `POST /control` | a [`Control`] as JSON: play, pause, speed, seek (a replay) |
//! | `POST /send` | `{"red_below_mm": R, "yellow_below_mm": Y}`: a `ThresholdConfig` frame on the bus |
//!
//! A refused request is answered with its reason: 415 for a body not sent as
//! `application/json`, 400 for malformed JSON, 422 for JSON of the wrong shape or a
//! threshold pair the ECU would refuse, 413 above [`BODY_MAX`] bytes, 409 for what the
//! feed cannot do (a live bus has no clock, a replay no bus), 502 when the bus fails to
//! take a frame, 503 when [`MAX_STREAMS`] event streams already run. A client that leaves
//! ends its stream; the server keeps nothing of it, so its memory is bounded whatever the
//! clients do.
//!
//! Listening on a loopback address, the server answers only requests addressed to a
//! loopback name (`127.0.0.1`, `localhost`, `[::1]`), so that a web page whose domain is
//! re-resolved to this machine (DNS rebinding) is refused; and it refuses a `POST` whose
//! `Origin` is another site's (403).

use std::convert::Infallible;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::Duration;

use axum::extract::{DefaultBodyLimit, Request, State};
use axum::http::{header, Method, StatusCode};
use axum::middleware::Next;
use axum::response::sse::{Event, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use futures_util::stream::{self, Stream};
use serde::Deserialize;
use tokio::sync::watch;

use super::feed::{Control, Feed, SendError, Shared, Snapshot};
use super::state::Thresholds;
use crate::codec::{self, Input};
use crate::dbc::MessageDef;

/// How often a stream sends the picture (20 per second).
pub const EVENT_PERIOD: Duration = Duration::from_millis(50);

/// How often the replay's clock moves.
const TICK: Duration = Duration::from_millis(10);

/// The most event streams at once.
pub const MAX_STREAMS: usize = 32;

/// The longest request body read (a control or a send is a few dozen bytes).
pub const BODY_MAX: usize = 4096;

const PAGE: &str = include_str!("assets/index.html");
const SCRIPT: &str = include_str!("assets/view.js");
const STYLE: &str = include_str!("assets/view.css");

/// The feed, whatever a task that held it did (each change to it is whole).
fn lock(feed: &Mutex<Feed>) -> MutexGuard<'_, Feed> {
    feed.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The sender panel's request.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SendRequest {
    red_below_mm: u32,
    yellow_below_mm: u32,
}

/// What every request handler shares.
#[derive(Clone)]
struct App {
    feed: Shared,
    config: Option<Arc<MessageDef>>,
    loopback_only: bool,
    streams: Arc<AtomicUsize>,
    stop: watch::Receiver<bool>,
}

impl App {
    fn snapshot(&self) -> Snapshot {
        let mut snapshot = lock(&self.feed).snapshot();
        snapshot.streams = self.streams.load(Ordering::SeqCst);
        snapshot.can_send &= self.config.is_some();
        snapshot
    }
}

/// A running view: its address, and the way to stop it.
pub struct View {
    listener: std::net::TcpListener,
    app: App,
    stop: Stop,
}

/// Stops a [`View`] from another thread: its event streams end, then the server.
#[derive(Clone)]
pub struct Stop(Arc<watch::Sender<bool>>);

impl Stop {
    /// Ends [`View::run`].
    pub fn stop(&self) {
        self.0.send_replace(true);
    }
}

impl View {
    /// Listens on `addr` (`127.0.0.1:0` picks a free port) for the page of `feed`;
    /// `config` is the DBC's `ThresholdConfig`, which the sender panel encodes (none: the
    /// panel is off).
    ///
    /// # Errors
    /// The address cannot be bound.
    pub fn bind(addr: &str, feed: Shared, config: Option<MessageDef>) -> Result<Self, String> {
        let listener = std::net::TcpListener::bind(addr)
            .and_then(|l| l.set_nonblocking(true).map(|()| l))
            .map_err(|e| format!("cannot listen on {addr}: {e}"))?;
        let loopback_only = listener
            .local_addr()
            .map_err(|e| format!("{addr}: {e}"))?
            .ip()
            .is_loopback();
        let (stop, stopped) = watch::channel(false);
        Ok(Self {
            listener,
            app: App {
                feed,
                config: config.map(Arc::new),
                loopback_only,
                streams: Arc::new(AtomicUsize::new(0)),
                stop: stopped,
            },
            stop: Stop(Arc::new(stop)),
        })
    }

    /// The address it listens on.
    ///
    /// # Errors
    /// The socket cannot say (it always can once bound).
    pub fn addr(&self) -> Result<SocketAddr, String> {
        self.listener.local_addr().map_err(|e| e.to_string())
    }

    /// A handle that stops it.
    pub fn stopper(&self) -> Stop {
        self.stop.clone()
    }

    /// Answers requests until stopped.
    ///
    /// # Errors
    /// The runtime cannot start, or the listener fails.
    pub fn run(self) -> Result<(), String> {
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_io()
            .enable_time()
            .build()
            .map_err(|e| format!("cannot start the server's runtime: {e}"))?;
        let Self {
            listener,
            app,
            stop: _keep_open,
        } = self;
        runtime.block_on(async move {
            let listener =
                tokio::net::TcpListener::from_std(listener).map_err(|e| e.to_string())?;
            tokio::spawn(clock(Arc::clone(&app.feed), app.stop.clone()));
            let mut stopped = app.stop.clone();
            let router = Router::new()
                .route("/", get(page))
                .route("/index.html", get(page))
                .route("/view.js", get(script))
                .route("/view.css", get(style))
                .route("/state", get(state))
                .route("/events", get(events))
                .route("/control", post(control))
                .route("/send", post(send))
                .layer(DefaultBodyLimit::max(BODY_MAX))
                .layer(axum::middleware::from_fn_with_state(app.clone(), guard))
                .with_state(app);
            axum::serve(listener, router)
                .with_graceful_shutdown(async move {
                    let _ = stopped.wait_for(|stop| *stop).await;
                })
                .await
                .map_err(|e| format!("the view's server failed: {e}"))
        })
    }
}

/// Whether `host` (a `Host` header: a name, and maybe a port) names this machine's
/// loopback interface.
fn loopback_name(host: &str) -> bool {
    let name = match host.strip_prefix('[') {
        Some(v6) => v6.split(']').next().unwrap_or(""),
        None => host.split(':').next().unwrap_or(""),
    };
    matches!(name, "127.0.0.1" | "localhost" | "::1")
}

/// Why a request is refused, if it is: addressed to another name than a loopback one
/// (when listening on loopback), or a `POST` from another site's page.
fn refused(app: &App, request: &Request) -> Option<String> {
    let header = |name| {
        request
            .headers()
            .get(name)
            .map(|v: &axum::http::HeaderValue| v.to_str().unwrap_or("\u{fffd}"))
    };
    let host = header(header::HOST).unwrap_or("");
    if app.loopback_only && !loopback_name(host) {
        return Some(format!(
            "this view answers 127.0.0.1 or localhost, not `{host}`"
        ));
    }
    let origin = header(header::ORIGIN).filter(|_| request.method() == Method::POST)?;
    (origin != format!("http://{host}"))
        .then(|| format!("a request from `{origin}` may not control this view"))
}

async fn guard(State(app): State<App>, request: Request, next: Next) -> Response {
    match refused(&app, &request) {
        Some(why) => (StatusCode::FORBIDDEN, why).into_response(),
        None => next.run(request).await,
    }
}

/// Moves the replay's clock by the time that passed, every [`TICK`].
async fn clock(feed: Shared, stop: watch::Receiver<bool>) {
    let mut ticks = tokio::time::interval(TICK);
    let mut last = tokio::time::Instant::now();
    while !*stop.borrow() {
        let now = ticks.tick().await;
        lock(&feed).tick((now - last).as_secs_f64());
        last = now;
    }
}

fn file(content: &'static str, kind: &'static str) -> Response {
    (
        [
            (header::CONTENT_TYPE, kind),
            (header::CACHE_CONTROL, "no-store"),
        ],
        content,
    )
        .into_response()
}

async fn page() -> Response {
    file(PAGE, "text/html; charset=utf-8")
}

async fn script() -> Response {
    file(SCRIPT, "text/javascript; charset=utf-8")
}

async fn style() -> Response {
    file(STYLE, "text/css; charset=utf-8")
}

async fn state(State(app): State<App>) -> Response {
    ([(header::CACHE_CONTROL, "no-store")], Json(app.snapshot())).into_response()
}

fn done(result: Result<(), String>) -> Response {
    match result {
        Ok(()) => (StatusCode::OK, "ok").into_response(),
        Err(e) => (StatusCode::CONFLICT, e).into_response(),
    }
}

async fn control(State(app): State<App>, Json(control): Json<Control>) -> Response {
    done(lock(&app.feed).control(control))
}

async fn send(State(app): State<App>, Json(t): Json<SendRequest>) -> Response {
    let Some(config) = app.config.as_deref() else {
        return done(Err("the DBC has no `ThresholdConfig` message".into()));
    };
    // The ECU's own rule: it ignores a configuration that breaks it.
    if let Err(e) = cw_core::warning::Thresholds::new(t.red_below_mm, t.yellow_below_mm) {
        let why = match e {
            cw_core::warning::ThresholdError::RedIsZero => "red below 0 mm would never be red",
            cw_core::warning::ThresholdError::RedNotBelowYellow { .. } => {
                "red must be below yellow"
            }
        };
        return (StatusCode::UNPROCESSABLE_ENTITY, why).into_response();
    }
    let frame = codec::encode_frame(
        config,
        &[
            ("RedBelow".into(), Input::Int(t.red_below_mm.into())),
            ("YellowBelow".into(), Input::Int(t.yellow_below_mm.into())),
        ],
    );
    let thresholds = Thresholds {
        t: None,
        red_below_mm: t.red_below_mm,
        yellow_below_mm: t.yellow_below_mm,
    };
    match frame.map(|frame| lock(&app.feed).send(&frame, thresholds)) {
        Ok(Ok(())) => (StatusCode::OK, "ok").into_response(),
        Ok(Err(SendError::NoBus(why))) => (StatusCode::CONFLICT, why).into_response(),
        Ok(Err(SendError::Bus(why))) => (StatusCode::BAD_GATEWAY, why).into_response(),
        Err(e) => (StatusCode::UNPROCESSABLE_ENTITY, e).into_response(),
    }
}

/// Counts an event stream while it lives.
struct Counted(Arc<AtomicUsize>);

impl Drop for Counted {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

async fn events(State(app): State<App>) -> Response {
    if app.streams.fetch_add(1, Ordering::SeqCst) >= MAX_STREAMS {
        app.streams.fetch_sub(1, Ordering::SeqCst);
        return (StatusCode::SERVICE_UNAVAILABLE, "too many event streams").into_response();
    }
    let counted = Counted(Arc::clone(&app.streams));
    let mut ticks = tokio::time::interval(EVENT_PERIOD);
    ticks.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    // Ends when the server stops; a client that leaves drops it, and its count with it.
    let stream: std::pin::Pin<Box<dyn Stream<Item = Result<Event, Infallible>> + Send>> =
        Box::pin(stream::unfold(
            (app, ticks, counted),
            |(app, mut ticks, counted)| async move {
                ticks.tick().await;
                if *app.stop.borrow() {
                    return None;
                }
                let event = Event::default()
                    .json_data(app.snapshot())
                    .unwrap_or_else(|e| Event::default().event("error").data(e.to_string()));
                Some((Ok(event), (app, ticks, counted)))
            },
        ));
    ([(header::CACHE_CONTROL, "no-store")], Sse::new(stream)).into_response()
}

#[cfg(test)]
mod tests;
