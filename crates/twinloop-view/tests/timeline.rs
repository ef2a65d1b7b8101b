//! The timeline in a real headless browser, driven by real input (DevTools protocol
//! mouse and keyboard events, as a user's): one-sample steps move to the next and the
//! previous row of the recording; play advances time at the rate of the browser's
//! clock, and the speed menu multiplies that rate; pause stops it; the ghost's offset
//! slider shifts the row the ghost shows by the offset; picking a column in the plot's
//! list adds its series, with the recording's values.
//!
//! Without Chromium these tests print why and pass, unless
//! TWINLOOP_REQUIRE_ORACLES=1 (CI), where a missing browser fails them.

use serde_json::Value;
use std::path::Path;
use std::time::{Duration, Instant};
use twinloop_io::Table;
use twinloop_view::{Content, Recording, Scene};

#[path = "support/cdp.rs"]
mod cdp;
#[path = "support/chromium.rs"]
mod chromium;
#[allow(dead_code)]
#[path = "support/page.rs"]
mod page;
use chromium::browser;
use page::{km20, pose_a, serve_with_misses};

/// 20 s of km20 at 100 Hz: the left knee swinging, a `tau:l_knee` column, the base
/// moving along x at `drift` m/s from `x0` (so the row a robot shows is seen in its
/// base position).
fn run(model: &twinloop_dynamics::Model, knee: f64, x0: f64, drift: f64, tau: bool) -> Table {
    let names = model.q_names();
    let mut columns = vec!["t".to_string()];
    columns.extend(names.iter().map(|n| format!("q:{n}")));
    if tau {
        columns.push("tau:l_knee".into());
    }
    let k = names.iter().position(|n| n == "l_knee").unwrap();
    let mut table = Table::new(columns);
    for i in 0..=2000 {
        let t = 0.01 * i as f64;
        let mut q = pose_a(model);
        q[0] = x0 + drift * t;
        q[k] = knee + 0.5 * t.sin();
        let mut row = vec![t];
        row.extend(q);
        if tau {
            row.push(t.cos());
        }
        table.rows.push(row);
    }
    table
}

/// A column as the page holds it (f32).
fn column(table: &Table, name: &str) -> Vec<f64> {
    let c = table.column_index(name).unwrap();
    table.rows.iter().map(|r| r[c] as f32 as f64).collect()
}

/// The last row at or before `t`, as the page finds it.
fn row_at(times: &[f64], t: f64) -> usize {
    times.iter().rposition(|&x| x <= t).unwrap_or(0)
}

fn timeline(page: &mut cdp::Browser) -> Value {
    let text = page.eval("JSON.stringify(window.twinloop.timeline)");
    serde_json::from_str(text.as_str().unwrap()).unwrap()
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// Play for `wall` and return (rate of the page's time per second of the browser's
/// frame clock, per second of this process's clock).
fn rate(page: &mut cdp::Browser, wall: Duration) -> (f64, f64) {
    page.wait_for("window.twinloop.timeline.frame_time !== null", 20);
    let a = timeline(page);
    let start = Instant::now();
    std::thread::sleep(wall);
    let b = timeline(page);
    let elapsed = start.elapsed().as_secs_f64();
    let dt = num(&b["now"]) - num(&a["now"]);
    (
        dt / ((num(&b["frame_time"]) - num(&a["frame_time"])) / 1e3),
        dt / elapsed,
    )
}

#[test]
fn play_speed_step_offset_and_column_picking_do_what_they_say() {
    let Some(chromium) = browser() else { return };
    let (robot, model) = km20();
    let scene = Scene::new(&robot, None, &[]);
    let real = run(&model, 0.0, 0.0, 0.01, true);
    let sim = run(&model, 0.3, 0.4, 0.02, false);
    let times = column(&real, "t");
    let ghost_x = column(&sim, "q:base.x");
    let recordings = vec![
        Recording::from_table(&real, Path::new("real.csv"), &scene.info).unwrap(),
        Recording::from_table(&sim, Path::new("sim.csv"), &scene.info).unwrap(),
    ];
    let (url, misses) = serve_with_misses(Content {
        scene,
        recordings,
        live: None,
    });
    let mut page = cdp::Browser::open(&chromium, &format!("{url}?t=2"));
    page.wait_for("!!(window.twinloop && window.twinloop.ready)", 120);
    let tl = timeline(&mut page);
    assert_eq!(num(&tl["now"]), 2.0, "{tl}");
    assert_eq!(tl["actors"][0]["sample"], 200, "{tl}");

    // One sample forward, two back: the rows next to it, at their recorded times.
    for (button, row) in [("#step-fwd", 201), ("#step-back", 200), ("#step-back", 199)] {
        let (x, y, _) = page.centre(button);
        page.click(x, y);
        page.wait_for(
            &format!("window.twinloop.timeline.actors[0].sample === {row}"),
            20,
        );
        let tl = timeline(&mut page);
        assert_eq!(num(&tl["now"]), times[row], "{button}: {tl}");
        assert_eq!(num(&tl["actors"][0]["t"]), times[row]);
        // The clock says it at once (not at the next 10 Hz update).
        assert_eq!(tl["clock"], format!("{:.3} s", times[row]));
    }

    // Play: the page's time runs at the rate of the browser's clock.
    let (x, y, _) = page.centre("#play");
    page.click(x, y);
    page.wait_for("window.twinloop.timeline.playing", 20);
    let (frames, wall) = rate(&mut page, Duration::from_secs(2));
    assert!(
        (frames - 1.0).abs() < 0.02,
        "1x: {frames} s per s of frames"
    );
    assert!(
        (0.7..1.3).contains(&wall),
        "1x: {wall} s per s of wall time"
    );

    // Speed: the menu from the keyboard, 1x -> 2x -> 4x; time runs four times faster.
    page.eval("document.getElementById('speed').focus()");
    for _ in 0..2 {
        page.key("ArrowDown", "ArrowDown", 40);
    }
    page.wait_for("window.twinloop.timeline.speed === 4", 20);
    let (frames, wall) = rate(&mut page, Duration::from_secs(2));
    assert!(
        (frames - 4.0).abs() < 0.08,
        "4x: {frames} s per s of frames"
    );
    assert!(
        (2.8..5.2).contains(&wall),
        "4x: {wall} s per s of wall time"
    );

    // Pause: time stands.
    let (x, y, _) = page.centre("#play");
    page.click(x, y);
    page.wait_for("!window.twinloop.timeline.playing", 20);
    let before = num(&timeline(&mut page)["now"]);
    std::thread::sleep(Duration::from_millis(500));
    let tl = timeline(&mut page);
    assert_eq!(num(&tl["now"]), before, "paused: {tl}");

    // The ghost's offset slider: the ghost shows its row at now - offset, the robot
    // its row at now.
    let (x, y, width) = page.centre("input.offset");
    assert!(width > 20.0, "offset slider {width} px wide");
    page.click(x + 0.3 * width, y);
    page.wait_for("window.twinloop.timeline.actors[1].offset !== 0", 20);
    // The robots are posed at the next frame drawn: look until it is there.
    let start = Instant::now();
    let (tl, main_row, ghost_row) = loop {
        let tl = timeline(&mut page);
        let (now, offset) = (num(&tl["now"]), num(&tl["actors"][1]["offset"]));
        let (main_row, ghost_row) = (row_at(&times, now), row_at(&times, now - offset));
        if tl["actors"][1]["sample"] == ghost_row || start.elapsed() > Duration::from_secs(20) {
            assert!(offset > 1.0, "offset {offset} s");
            assert_eq!(tl["actors"][0]["sample"], main_row, "{tl}");
            assert_eq!(tl["actors"][1]["sample"], ghost_row, "{tl}");
            break (tl, main_row, ghost_row);
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(main_row - ghost_row > 100, "{main_row} {ghost_row}");
    // The ghost is drawn there: its base where that row puts it.
    assert_eq!(num(&tl["actors"][1]["base"][0]), ghost_x[ghost_row], "{tl}");

    // Column picking: filter, then Ctrl+click the one option left.
    let before = tl["plot"].as_array().unwrap().len();
    let (x, y, _) = page.centre("#plot-filter");
    page.click(x, y);
    page.type_text("tau:");
    page.wait_for(
        "[...document.getElementById('plot-columns').options].filter((o) => !o.hidden).length === 1",
        20,
    );
    let (x, y) = first_visible_option(&mut page);
    page.click_with(x, y, 2);
    page.wait_for(
        &format!("window.twinloop.timeline.plot.length === {}", before + 1),
        20,
    );
    let plot = timeline(&mut page)["plot"].clone();
    let tau = plot
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["label"] == "1: tau:l_knee")
        .unwrap_or_else(|| panic!("no tau:l_knee series in {plot}"));
    let want = column(&real, "tau:l_knee");
    assert_eq!(tau["n"], want.len());
    assert_eq!(num(&tau["first"]), want[0]);
    assert_eq!(num(&tau["last"]), want[want.len() - 1]);

    let errors = page.eval("JSON.stringify(window.twinloop.errors)");
    assert_eq!(errors, Value::String("[]".into()));
    assert_eq!(misses.list(), Vec::<String>::new());
}

/// Where the first option not filtered out is drawn in the plot's column list.
fn first_visible_option(page: &mut cdp::Browser) -> (f64, f64) {
    let r = page.eval(
        "(() => { const s = document.getElementById('plot-columns'); s.scrollIntoView({ block: 'center' }); \
         const o = [...s.options].find((o) => !o.hidden); const r = o.getBoundingClientRect(); \
         return [r.left + Math.min(r.width / 2, 40), r.top + r.height / 2, r.height]; })()",
    );
    let v: Vec<f64> = r
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(v[2] > 0.0, "the option is not drawn: {r}");
    (v[0], v[1])
}
