//! The viewer's HTTP server: the embedded page, `scene.json`, `robot.urdf`, the
//! meshes the description names (by number) and the recordings. Every URL is
//! matched whole against this fixed set; nothing in a request path is ever joined
//! to a file path, so `../` or `%2e%2e` can only miss (404).

use crate::assets;
use crate::live::{LiveFeed, LiveFrame};
use crate::recording::{Recording, RecordingInfo};
use crate::scene::{Scene, SceneInfo};
use serde::Serialize;
use std::io;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;
use tiny_http::{Header, Request, Response, StatusCode};

/// Everything the server hands out.
pub struct Content {
    pub scene: Scene,
    pub recordings: Vec<Recording>,
    /// The live state behind `/live`, when something publishes one.
    pub live: Option<LiveFeed>,
}

/// `scene.json`: the scene and the list of recordings.
#[derive(Serialize)]
pub struct PageData<'a> {
    #[serde(flatten)]
    pub scene: &'a SceneInfo,
    pub recordings: Vec<&'a RecordingInfo>,
    /// Whether the page should connect to `/live`.
    pub live: bool,
}

impl Content {
    pub fn page_data(&self) -> PageData<'_> {
        PageData {
            scene: &self.scene.info,
            recordings: self.recordings.iter().map(|r| &r.info).collect(),
            live: self.live.is_some(),
        }
    }

    /// The answer to a GET of `url` (path and query): (MIME type, body), or None (404).
    pub fn get(&self, url: &str) -> Option<(&'static str, Vec<u8>)> {
        let path = url.split(['?', '#']).next().unwrap_or("");
        if let Some(a) = assets::find(path) {
            return Some((a.mime, a.body.as_bytes().to_vec()));
        }
        match path {
            "/scene.json" => {
                let json = serde_json::to_vec(&self.page_data()).ok()?;
                return Some(("application/json", json));
            }
            "/robot.urdf" => {
                return Some(("application/xml", self.scene.urdf.as_bytes().to_vec()));
            }
            _ => {}
        }
        if path.starts_with("/mesh/") {
            let mesh = self
                .scene
                .info
                .meshes
                .iter()
                .find(|m| m.url.as_deref() == Some(&path[1..]))?;
            let bytes = std::fs::read(mesh.path.as_ref()?).ok()?;
            return Some(("application/octet-stream", bytes));
        }
        if let Some(rest) = path.strip_prefix("/recording/") {
            let (index, ext) = rest.split_once('.')?;
            if index.is_empty() || !index.bytes().all(|b| b.is_ascii_digit()) {
                return None;
            }
            let rec = self.recordings.get(index.parse::<usize>().ok()?)?;
            return match ext {
                "json" => Some(("application/json", serde_json::to_vec(&rec.info).ok()?)),
                "bin" => Some(("application/octet-stream", rec.data.clone())),
                _ => None,
            };
        }
        None
    }
}

/// A running server; `run` answers requests until the process ends.
pub struct Server {
    http: Arc<tiny_http::Server>,
    content: Arc<Content>,
    misses: Misses,
}

/// How many requests are answered at once (the page loads meshes in parallel).
const WORKERS: usize = 4;

/// Send each live frame at once: without TCP_NODELAY a small frame waits for the
/// ACK of the one before (Nagle), which a page that only reads sends late (delayed
/// ACK, up to 40 ms on Linux): that was much of the tail of the live lag on arrival.
/// Set on the listener: the connections tiny_http accepts inherit it on Linux. Best
/// effort (without it frames still arrive, later).
fn no_delay(listener: &std::net::TcpListener) {
    #[cfg(unix)]
    {
        use std::os::fd::AsRawFd;
        let _ = nix::sys::socket::setsockopt(
            listener.as_raw_fd(),
            nix::sys::socket::sockopt::TcpNoDelay,
            &true,
        );
    }
    #[cfg(not(unix))]
    let _ = listener;
}

impl Server {
    /// Bind to `addr` (`127.0.0.1:0` picks a free port).
    pub fn bind(addr: &str, content: Content) -> io::Result<Server> {
        let listener = std::net::TcpListener::bind(addr)?;
        no_delay(&listener);
        let http = tiny_http::Server::from_listener(listener, None).map_err(io::Error::other)?;
        Ok(Server {
            http: Arc::new(http),
            content: Arc::new(content),
            misses: Misses::default(),
        })
    }

    /// The address bound.
    pub fn addr(&self) -> SocketAddr {
        match self.http.server_addr() {
            tiny_http::ListenAddr::IP(a) => a,
            #[allow(unreachable_patterns)]
            _ => SocketAddr::from(([127, 0, 0, 1], 0)),
        }
    }

    /// What was asked for and not found so far.
    pub fn misses(&self) -> Misses {
        self.misses.clone()
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr())
    }

    /// Answer requests on worker threads, in the background.
    pub fn spawn(&self) {
        for _ in 0..WORKERS {
            let http = Arc::clone(&self.http);
            let content = Arc::clone(&self.content);
            let misses = self.misses.clone();
            std::thread::spawn(move || {
                while let Ok(request) = http.recv() {
                    respond(&content, &misses, request);
                }
            });
        }
    }

    /// Answer requests on this thread and the workers, until the process ends.
    pub fn run(&self) {
        self.spawn();
        while let Ok(request) = self.http.recv() {
            respond(&self.content, &self.misses, request);
        }
    }
}

/// At most this many pages follow the live view at once.
const MAX_LIVE_CLIENTS: usize = 8;

/// The paths answered 404, oldest first (at most [`MAX_MISSES`]): a page that
/// asks for something the server does not have is a bug the tests look for.
#[derive(Clone, Default)]
pub struct Misses(Arc<std::sync::Mutex<Vec<String>>>);

const MAX_MISSES: usize = 100;

impl Misses {
    pub fn list(&self) -> Vec<String> {
        self.0.lock().map(|m| m.clone()).unwrap_or_default()
    }

    fn record(&self, path: &str) {
        if let Ok(mut m) = self.0.lock()
            && m.len() < MAX_MISSES
        {
            m.push(path.to_string());
        }
    }
}

fn respond(content: &Content, misses: &Misses, request: Request) {
    if request.url() == "/live"
        && let Some(feed) = &content.live
    {
        return live_client(feed, request);
    }
    let header = |k: &str, v: &str| {
        Header::from_bytes(k.as_bytes(), v.as_bytes())
            .unwrap_or_else(|()| unreachable!("header {k} is ASCII"))
    };
    let answer = match request.method() {
        tiny_http::Method::Get | tiny_http::Method::Head => content.get(request.url()),
        _ => None,
    };
    // A client that went away mid-answer is its own business: the error is dropped
    // and the server goes on.
    let _ = match answer {
        Some((mime, body)) => {
            // Content-Length rather than chunks: the page can show progress.
            let mut r = Response::from_data(body).with_chunked_threshold(usize::MAX);
            r.add_header(header("Content-Type", mime));
            r.add_header(header("Cache-Control", "no-store"));
            request.respond(r)
        }
        None => {
            misses.record(request.url());
            request.respond(Response::from_string("not found\n").with_status_code(StatusCode(404)))
        }
    };
}

/// Upgrade `/live` to a websocket and send it the newest state whenever there is
/// one, on its own thread. A client that goes away ends its thread; the server and
/// the other clients go on.
fn live_client(feed: &LiveFeed, request: Request) {
    let key = request
        .headers()
        .iter()
        .find(|h| h.field.equiv("Sec-WebSocket-Key"))
        .map(|h| h.value.as_str().to_string());
    let Some(key) = key else {
        let _ = request.respond(Response::from_string("websocket only\n").with_status_code(400));
        return;
    };
    if !feed.join(MAX_LIVE_CLIENTS) {
        let _ =
            request.respond(Response::from_string("too many live pages\n").with_status_code(503));
        return;
    }
    let accept = tungstenite::handshake::derive_accept_key(key.as_bytes());
    let header = |k: &str, v: &str| {
        Header::from_bytes(k.as_bytes(), v.as_bytes())
            .unwrap_or_else(|()| unreachable!("header {k} is ASCII"))
    };
    let response = Response::empty(StatusCode(101))
        .with_header(header("Upgrade", "websocket"))
        .with_header(header("Connection", "Upgrade"))
        .with_header(header("Sec-WebSocket-Accept", &accept));
    let stream = request.upgrade("websocket", response);
    let feed = feed.clone();
    std::thread::spawn(move || {
        let mut ws = tungstenite::WebSocket::from_raw_socket(
            stream,
            tungstenite::protocol::Role::Server,
            None,
        );
        let mut seen = 0;
        let mut frame = LiveFrame::default();
        while !feed.is_closed() {
            // Wake now and then even without news, to notice a client gone quiet.
            let Some(seq) = feed.next(seen, Duration::from_millis(500), &mut frame) else {
                if ws
                    .send(tungstenite::Message::Ping(Vec::new().into()))
                    .is_err()
                {
                    break;
                }
                continue;
            };
            seen = seq;
            // Non-finite numbers are not JSON: serde_json writes them as null, which
            // the page reads as "not known".
            let json = serde_json::to_string(&frame).unwrap_or_default();
            if ws.send(tungstenite::Message::Text(json.into())).is_err() {
                break;
            }
        }
        let _ = ws.close(None);
        let _ = ws.flush();
        feed.leave();
    });
}
