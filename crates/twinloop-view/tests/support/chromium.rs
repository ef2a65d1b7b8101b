//! Headless Chromium for the browser tests (shared by twinloop-view's and
//! twinloop-cli's): find it, load a page with software WebGL, and read the DOM it
//! leaves (the page writes its status into `<pre id="status">`).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Chromium: TWINLOOP_CHROMIUM, else the first on PATH.
pub fn find_chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("TWINLOOP_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    for dir in std::env::split_paths(&path) {
        for name in ["chromium", "chromium-browser", "google-chrome", "chrome"] {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// The browser, or None (skip) when there is none and CI does not require it.
pub fn browser() -> Option<PathBuf> {
    let found = find_chromium();
    if found.is_none() {
        let why = "no chromium on PATH (apt-get install -y chromium, or set TWINLOOP_CHROMIUM)";
        if std::env::var("TWINLOOP_REQUIRE_ORACLES").as_deref() == Ok("1") {
            panic!("TWINLOOP_REQUIRE_ORACLES=1 and {why}");
        }
        // Straight to stderr: the test harness would swallow eprintln! of a passing test.
        use std::io::Write;
        let _ = writeln!(std::io::stderr(), "skipped: {why}");
    }
    found
}

pub fn unescape_html(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&amp;", "&")
}

pub fn element_text<'a>(dom: &'a str, id: &str) -> Option<&'a str> {
    let start = dom.find(&format!("<pre id=\"{id}\""))?;
    let open_end = start + dom[start..].find('>')? + 1;
    let close = open_end + dom[open_end..].find("</pre>")?;
    Some(&dom[open_end..close])
}

/// Load `url` (software WebGL, 640x480, up to 20 s of the page's virtual time) and
/// return the DOM it leaves. Headless Chromium with a virtual-time budget now and
/// then never exits on a loaded machine (seen once in a CI run of twelve pages at
/// once, each page alone loading in 2 s): a browser that has not finished in 120 s
/// is killed and the page loaded once more in a fresh profile; the DOM is judged as
/// before, so a broken page still fails.
pub fn dump_dom(chromium: &Path, url: &str) -> String {
    for attempt in 1..=2 {
        if let Some(dom) = dump_dom_once(chromium, url, Duration::from_secs(120)) {
            return dom;
        }
        eprintln!("chromium did not finish with {url} in 120 s (attempt {attempt} of 2)");
    }
    panic!("chromium did not finish with {url} in two attempts of 120 s");
}

fn dump_dom_once(chromium: &Path, url: &str, limit: Duration) -> Option<String> {
    let profile = tempdir("chromium-profile");
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
            "--virtual-time-budget=20000",
            "--dump-dom",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(url)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut stdout, &mut s).unwrap();
        s
    });
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            let _ = std::fs::remove_dir_all(&profile);
            return None;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let dom = reader.join().unwrap();
    let _ = std::fs::remove_dir_all(&profile);
    Some(dom)
}

pub fn tempdir(what: &str) -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static N: AtomicUsize = AtomicUsize::new(0);
    let d = std::env::temp_dir().join(format!(
        "twinloop-view-{what}-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}
