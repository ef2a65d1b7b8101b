//! Headless Chromium driven over the DevTools protocol, for the tests that need real
//! input (a mouse click goes through the browser's hit testing, like a user's).

use serde_json::{Value, json};
use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tungstenite::{Message, WebSocket};

/// One browser with one page open, killed when dropped.
pub struct Browser {
    child: Child,
    ws: WebSocket<TcpStream>,
    session: String,
    next_id: u64,
    profile: PathBuf,
    /// What the page wrote to its console: (level, text), in order.
    pub console: Vec<(String, String)>,
}

impl Browser {
    /// Start `chromium` (software WebGL, 640x480) on `url`, listening to its console.
    pub fn open(chromium: &Path, url: &str) -> Browser {
        let profile = super::chromium::tempdir("cdp-profile");
        let mut child = Command::new(chromium)
            .args([
                "--headless",
                "--no-sandbox",
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--no-first-run",
                "--window-size=640,480",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // "DevTools listening on ws://127.0.0.1:PORT/devtools/browser/ID"
        let mut err = BufReader::new(child.stderr.take().unwrap());
        let mut line = String::new();
        let ws_url = loop {
            line.clear();
            if err.read_line(&mut line).unwrap() == 0 {
                let _ = child.kill();
                panic!("chromium ended without a DevTools address");
            }
            if let Some(at) = line.find("ws://") {
                break line[at..].trim().to_string();
            }
        };
        // Keep reading stderr so the browser never blocks on a full pipe.
        std::thread::spawn(move || {
            let mut sink = String::new();
            while err.read_line(&mut sink).unwrap_or(0) > 0 {
                sink.clear();
            }
        });
        let host = ws_url["ws://".len()..]
            .split('/')
            .next()
            .unwrap()
            .to_string();
        let stream = TcpStream::connect(&host).unwrap();
        let (ws, _) = tungstenite::client(ws_url.as_str(), stream).unwrap();
        let mut b = Browser {
            child,
            ws,
            session: String::new(),
            next_id: 0,
            profile,
            console: Vec::new(),
        };
        let target = b.call("Target.createTarget", json!({ "url": "about:blank" }));
        let attached = b.call(
            "Target.attachToTarget",
            json!({ "targetId": target["targetId"], "flatten": true }),
        );
        b.session = attached["sessionId"].as_str().unwrap().to_string();
        // The console is listened to before the page loads.
        b.call("Runtime.enable", json!({}));
        b.call("Page.navigate", json!({ "url": url }));
        b
    }

    /// Send one command (to the page once attached) and wait for its answer.
    pub fn call(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut msg = json!({ "id": id, "method": method, "params": params });
        if !self.session.is_empty() {
            msg["sessionId"] = json!(self.session);
        }
        self.ws.send(Message::text(msg.to_string())).unwrap();
        loop {
            let Message::Text(text) = self.ws.read().unwrap() else {
                continue;
            };
            let v: Value = serde_json::from_str(text.as_str()).unwrap();
            if v["method"] == "Runtime.consoleAPICalled" {
                let p = &v["params"];
                let text: Vec<String> = p["args"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .map(|a| match &a["value"] {
                        Value::String(s) => s.clone(),
                        other => other.to_string(),
                    })
                    .collect();
                self.console
                    .push((p["type"].as_str().unwrap_or("").to_string(), text.join(" ")));
            }
            if v["id"] == json!(id) {
                assert!(v.get("error").is_none(), "{method}: {v}");
                return v["result"].clone();
            }
        }
    }

    /// The value of a JavaScript expression in the page (JSON-able).
    pub fn eval(&mut self, expression: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({ "expression": expression, "returnByValue": true }),
        );
        r["result"]["value"].clone()
    }

    /// Wait until `expression` is true in the page, for up to `seconds`.
    pub fn wait_for(&mut self, expression: &str, seconds: u64) {
        let start = Instant::now();
        while self.eval(expression) != json!(true) {
            assert!(
                start.elapsed() < Duration::from_secs(seconds),
                "the page did not get to `{expression}` in {seconds} s: {}",
                self.eval("JSON.stringify(window.twinloop)")
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// A left click at (x, y), CSS pixels of the viewport: press and release.
    pub fn click(&mut self, x: f64, y: f64) {
        self.click_with(x, y, 0);
    }

    /// A left click at (x, y) with modifier keys held (1 Alt, 2 Ctrl, 4 Meta, 8 Shift).
    pub fn click_with(&mut self, x: f64, y: f64, modifiers: u32) {
        for kind in ["mouseMoved", "mousePressed", "mouseReleased"] {
            self.call(
                "Input.dispatchMouseEvent",
                json!({ "type": kind, "x": x, "y": y, "button": "left", "clickCount": 1, "modifiers": modifiers }),
            );
        }
    }

    /// A key pressed and released on the focused element: `key` as the DOM names it
    /// (e.g. "ArrowDown"), `code` the physical key, `key_code` its Windows code.
    pub fn key(&mut self, key: &str, code: &str, key_code: u32) {
        for kind in ["rawKeyDown", "keyUp"] {
            self.call(
                "Input.dispatchKeyEvent",
                json!({ "type": kind, "key": key, "code": code, "windowsVirtualKeyCode": key_code }),
            );
        }
    }

    /// Text typed into the focused element.
    pub fn type_text(&mut self, text: &str) {
        self.call("Input.insertText", json!({ "text": text }));
    }

    /// The centre (x, y) of the element `selector` and its width, after scrolling it
    /// into view; the width is 0 when it is not drawn.
    pub fn centre(&mut self, selector: &str) -> (f64, f64, f64) {
        let r = self.eval(&format!(
            "(() => {{ const e = document.querySelector({selector:?}); e.scrollIntoView({{ block: 'center' }}); \
             const r = e.getBoundingClientRect(); return [r.left + r.width / 2, r.top + r.height / 2, r.width]; }})()"
        ));
        let v: Vec<f64> = r
            .as_array()
            .unwrap_or_else(|| panic!("no {selector}: {r}"))
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        (v[0], v[1], v[2])
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.profile);
    }
}
