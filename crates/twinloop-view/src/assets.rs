//! The page's static files, compiled into the binary: the page itself and the
//! vendored libraries (see VENDOR.md). Nothing is read from disk at run time.

/// A static file: its URL path (no leading `/`), MIME type and bytes.
pub struct Asset {
    pub path: &'static str,
    pub mime: &'static str,
    pub body: &'static str,
}

pub const INDEX: Asset = Asset {
    path: "index.html",
    mime: "text/html; charset=utf-8",
    body: include_str!("../web/index.html"),
};
pub const VIEWER_JS: Asset = Asset {
    path: "viewer.js",
    mime: "text/javascript; charset=utf-8",
    body: include_str!("../web/viewer.js"),
};
pub const VIEWER_CSS: Asset = Asset {
    path: "viewer.css",
    mime: "text/css; charset=utf-8",
    body: include_str!("../web/viewer.css"),
};
pub const VENDOR_JS: Asset = Asset {
    path: "vendor/twinloop-vendor.js",
    mime: "text/javascript; charset=utf-8",
    body: include_str!("../web/vendor/twinloop-vendor.js"),
};
pub const UPLOT_CSS: Asset = Asset {
    path: "vendor/uPlot.min.css",
    mime: "text/css; charset=utf-8",
    body: include_str!("../web/vendor/uPlot.min.css"),
};

pub const ALL: [&Asset; 5] = [&INDEX, &VIEWER_JS, &VIEWER_CSS, &VENDOR_JS, &UPLOT_CSS];

/// The asset at a URL path (`/` is the page).
pub fn find(path: &str) -> Option<&'static Asset> {
    let path = path.strip_prefix('/').unwrap_or(path);
    let path = if path.is_empty() { "index.html" } else { path };
    ALL.into_iter().find(|a| a.path == path)
}
