//! The 3D web viewer of `twinloop view`: a robot (URDF, MJCF or built-in) in the
//! browser with its recordings replayed, ghosts, overlays and plots.
//!
//! - `scene`: the description made ready for the page (served URDF, meshes by
//!   number, link and joint facts);
//! - `inertia_box`: the equivalent box of a link's inertia;
//! - `recording`: a CSV as column-major f32 and its missing joint columns;
//! - `server`: the loopback HTTP server (tiny_http) and its fixed set of URLs;
//! - `live`: the newest state of a running source, sent to pages over a websocket
//!   (no queue: decimated, latest only), and following a CSV as it is written;
//! - `publisher`: a running command's own live view (`simulate --view`, ...);
//! - `export`: one self-contained HTML file;
//! - `assets`: the page and the vendored three.js, urdf-loader and uPlot
//!   (`web/`, see VENDOR.md), compiled in.

pub mod assets;
pub mod export;
pub mod inertia_box;
pub mod live;
pub mod publisher;
pub mod recording;
pub mod scene;
pub mod server;

pub use export::export_html;
pub use live::{Decimator, LiveFeed, follow_csv};
pub use publisher::{LivePublisher, PublisherStats};
pub use recording::{Recording, RecordingInfo};
pub use scene::{PackageDir, Scene, SceneError, SceneInfo};
pub use server::{Content, Server};
