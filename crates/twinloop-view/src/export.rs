//! `--export replay.html`: the page, its libraries, the robot, its meshes and the
//! recordings in one HTML file that opens offline. The page's loader reads
//! `window.TWINLOOP_EMBED` in place of the server's URLs.

use crate::assets;
use crate::server::Content;
use base64::Engine;
use base64::engine::general_purpose::STANDARD;
use std::collections::BTreeMap;
use std::io;

/// Text safe inside a `<script>` element: `</` cannot close it early (`<\/` means
/// the same in JSON strings and in the vendored JS, which has no `</` outside strings).
fn script_safe(text: &str) -> String {
    text.replace("</", "<\\/")
}

/// The self-contained HTML of `content`. A mesh that cannot be read now is an
/// error naming it.
pub fn export_html(content: &Content) -> io::Result<String> {
    let mut meshes = BTreeMap::new();
    for m in &content.scene.info.meshes {
        if let (Some(url), Some(path)) = (&m.url, &m.path) {
            let bytes = std::fs::read(path)
                .map_err(|e| io::Error::new(e.kind(), format!("{}: {e}", path.display())))?;
            meshes.insert(url.clone(), STANDARD.encode(bytes));
        }
    }
    let recordings: Vec<serde_json::Value> = content
        .recordings
        .iter()
        .map(|r| serde_json::json!({"info": r.info, "data": STANDARD.encode(&r.data)}))
        .collect();
    let embed = serde_json::json!({
        "scene": content.page_data(),
        "urdf": content.scene.urdf,
        "meshes": meshes,
        "recordings": recordings,
    });
    let page = assets::INDEX.body;
    let inline_css = format!(
        "<style>\n{}\n{}\n</style>",
        assets::UPLOT_CSS.body,
        assets::VIEWER_CSS.body
    );
    let inline_js = format!(
        "<script>{}</script>\n<script>window.TWINLOOP_EMBED = {};</script>\n<script>{}</script>",
        script_safe(assets::VENDOR_JS.body),
        script_safe(&embed.to_string()),
        script_safe(assets::VIEWER_JS.body)
    );
    // The page marks where its files go; replace the links by the files.
    let (head, rest) = page
        .split_once("<!--styles-->")
        .ok_or_else(|| io::Error::other("index.html lacks <!--styles-->"))?;
    let (_, rest) = rest
        .split_once("<!--/styles-->")
        .ok_or_else(|| io::Error::other("index.html lacks <!--/styles-->"))?;
    let (middle, rest) = rest
        .split_once("<!--scripts-->")
        .ok_or_else(|| io::Error::other("index.html lacks <!--scripts-->"))?;
    let (_, tail) = rest
        .split_once("<!--/scripts-->")
        .ok_or_else(|| io::Error::other("index.html lacks <!--/scripts-->"))?;
    Ok(format!("{head}{inline_css}{middle}{inline_js}{tail}"))
}
