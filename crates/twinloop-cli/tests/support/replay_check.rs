//! What `twinloop demo` writes for the 3D replay (`replay.html`, the ghosts of the
//! prior and adapted models on the robot's joint commands) checked against the bus
//! recording and the static angles the demo prints; the page opened in a real headless
//! Chromium. Used by cli_demo.rs on its km20 demo (one live demo for both checks) and
//! read_csv by cli_view.rs.

#![allow(dead_code)]

use std::path::Path;

/// The CSV's rows as numbers, and its header.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// The demo's replay files in `dir` and the report's link to them, against its
/// `tipover.csv` and the static angles on its terminal (`stdout`).
pub fn check_demo_replay(dir: &Path, stdout: &str) {
    let report = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(report.contains("<a href=\"replay.html\">"), "no link");
    // The ghosts: the adapted and prior models on the robot's joint commands, over
    // the recording's span, with the base pose the bus recording lacks.
    let (rec_header, rec) = read_csv(&dir.join("tipover.csv"));
    assert!(!rec_header.iter().any(|c| c.starts_with("q:base.")));
    let leans = leans_of(&rec_header, &rec);
    let direction_of = directions_of(&leans);
    // Each ghost's ankle angle at its fall, per lean, beside the static angles the
    // demo prints for the same model ("prior model (static, ...)", "adapted model (static, ...)").
    let mut tips = Vec::new();
    for (name, line) in [
        (
            "replay_prior.csv",
            "prior model (static, at the robot's onsets)",
        ),
        (
            "replay_adapted.csv",
            "adapted model (static, at the robot's onsets)",
        ),
    ] {
        let (header, rows) = read_csv(&dir.join(name));
        assert!(header.iter().any(|c| c == "q:base.qw"), "{name}");
        let end = rows.last().unwrap()[0];
        let rec_end = rec.last().unwrap()[0];
        assert!(
            (end - rec_end).abs() < 0.05,
            "{name} ends at {end}, the recording at {rec_end}"
        );
        let static_deg: Vec<f64> = stdout
            .lines()
            .find_map(|l| l.trim().strip_prefix(line))
            .unwrap_or_else(|| panic!("no {line:?} in {stdout}"))
            .split_whitespace()
            .map(|w| w.parse().unwrap())
            .collect();
        tips.push((
            ghost_falls(name, &header, &rows, &leans, &direction_of),
            static_deg,
        ));
    }
    // Each model tips at its own angle: where the static analysis puts the adapted
    // model's tip clearly before or after the prior's, its ghost tips before or after
    // too, in both leans of that direction.
    let (prior, adapted) = (&tips[0], &tips[1]);
    for d in 0..4 {
        let want = adapted.1[d] - prior.1[d];
        if want.abs() < 0.5 {
            continue;
        }
        for lean in (0..leans.len()).filter(|&k| direction_of[k] == d) {
            let got = adapted.0[lean] - prior.0[lean];
            assert!(
                got * want > 0.0,
                "lean {lean}: the ghosts tip at {:.2} (adapted) and {:.2} (prior) deg of \
                 ankle; statically {:.2} and {:.2}",
                adapted.0[lean],
                prior.0[lean],
                adapted.1[d],
                prior.1[d]
            );
        }
    }
    check_replay_page(dir);
}

/// Four directions, each a first ramp and two or three creeps, in order: a new
/// direction where the turned ankles or their sign change. Per lean, its direction.
fn directions_of(leans: &[Lean]) -> Vec<usize> {
    let mut direction_of = Vec::with_capacity(leans.len());
    for (k, l) in leans.iter().enumerate() {
        let same = k > 0 && {
            let p = &leans[k - 1];
            let mut a = p.ankles.clone();
            let mut b = l.ankles.clone();
            a.sort();
            b.sort();
            a == b && p.sign == l.sign
        };
        let d = direction_of.last().copied().unwrap_or(0) + usize::from(k > 0 && !same);
        direction_of.push(d);
    }
    assert_eq!(
        direction_of.last(),
        Some(&3),
        "four directions: {direction_of:?}"
    );
    for d in 0..4 {
        let n = direction_of.iter().filter(|&&x| x == d).count();
        assert!(
            // A first ramp, two or three creeps, and up to three creeps repeated
            // when spoiled (twinloop_ident::tipover_bus::MAX_SPOILED_CREEPS).
            (3..=7).contains(&n),
            "direction {d}: {n} leans ({direction_of:?})"
        );
    }
    direction_of
}

/// `replay.html` in a real headless Chromium: ready, no errors, the three recordings
/// with no joint missing (without Chromium it returns, unless the oracles are required).
fn check_replay_page(dir: &Path) {
    let Some(browser) = super::chromium::browser() else {
        return;
    };
    let page = format!(
        "file://{}?snapshot=1&t=1",
        dir.join("replay.html").display()
    );
    let dom = super::chromium::dump_dom(&browser, &page);
    let status = super::chromium::element_text(&dom, "status").expect("no #status");
    let status: serde_json::Value =
        serde_json::from_str(&super::chromium::unescape_html(status)).unwrap();
    assert_eq!(status["ready"], true, "{status}");
    assert_eq!(status["errors"].as_array().unwrap().len(), 0, "{status}");
    let recs = status["recordings"].as_array().unwrap();
    let names: Vec<&str> = recs.iter().map(|r| r["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        ["tipover.csv", "replay_adapted.csv", "replay_prior.csv"]
    );
    for r in recs {
        assert_eq!(r["missing"].as_array().unwrap().len(), 0, "{r}");
    }
}

/// One lean of a tip-over's bus recording: the rows from the last one commanding
/// the standing pose (every `goal:` as in the first row) before the goals leave it,
/// to the next lean's first; and the ankle joints it turned.
struct Lean {
    t0: f64,
    t1: f64,
    ankles: Vec<String>,
    /// Sign of the first turned ankle's goal from standing: with `ankles`, which of
    /// the four directions this lean is.
    sign: f64,
}

fn leans_of(header: &[String], rows: &[Vec<f64>]) -> Vec<Lean> {
    let goals: Vec<usize> = (0..header.len())
        .filter(|&i| header[i].starts_with("goal:"))
        .collect();
    let standing = |r: &Vec<f64>| goals.iter().all(|&i| r[i] == rows[0][i]);
    let mut out: Vec<Lean> = Vec::new();
    for k in 1..rows.len() {
        if standing(&rows[k]) {
            continue;
        }
        if standing(&rows[k - 1]) {
            if let Some(l) = out.last_mut() {
                l.t1 = rows[k - 1][0];
            }
            out.push(Lean {
                t0: rows[k - 1][0],
                t1: rows.last().unwrap()[0],
                ankles: Vec::new(),
                sign: 0.0,
            });
        }
        let l = out.last_mut().unwrap();
        for &i in &goals {
            let j = &header[i]["goal:".len()..];
            if rows[k][i] != rows[0][i] && j.contains("ank") && !l.ankles.iter().any(|a| a == j) {
                if l.ankles.is_empty() {
                    l.sign = (rows[k][i] - rows[0][i]).signum();
                }
                l.ankles.push(j.to_string());
            }
        }
    }
    out
}

/// A ghost's falls, one per lean (`direction_of` each: forward, backward, left,
/// right, as the tip-over runs them): standing at the lean's start, fallen (trunk 30 deg off
/// upright) towards the lean before the next starts; returns the mean ankle angle
/// of the lean's ankles at the fall (the largest before the trunk passed 30 deg),
/// deg.
fn ghost_falls(
    name: &str,
    header: &[String],
    rows: &[Vec<f64>],
    leans: &[Lean],
    direction_of: &[usize],
) -> Vec<f64> {
    let col = |c: &str| header.iter().position(|h| h == c).unwrap();
    let (qx, qy, qz, qw) = (
        col("q:base.qx"),
        col("q:base.qy"),
        col("q:base.qz"),
        col("q:base.qw"),
    );
    // Pitch (forward positive) and roll (right positive) of the trunk's up axis.
    let tilt = |r: &[f64]| {
        let (x, y, z, w) = (r[qx], r[qy], r[qz], r[qw]);
        let up = [
            2.0 * (x * z + w * y),
            2.0 * (y * z - w * x),
            1.0 - 2.0 * (x * x + y * y),
        ];
        (
            up[0].atan2(up[2]).to_degrees(),
            (-up[1]).atan2(up[2]).to_degrees(),
            up[2].clamp(-1.0, 1.0).acos().to_degrees(),
        )
    };
    let mut out = Vec::new();
    for (i, lean) in leans.iter().enumerate() {
        let part: Vec<&Vec<f64>> = rows
            .iter()
            .filter(|r| r[0] >= lean.t0 - 1e-9 && r[0] < lean.t1 - 1e-9)
            .collect();
        let (_, _, first) = tilt(part[0]);
        assert!(
            first < 3.0,
            "{name}, lean {i}: starts {first:.1} deg off upright"
        );
        let fall = part
            .iter()
            .position(|r| tilt(r).2 > 30.0)
            .unwrap_or_else(|| panic!("{name}, lean {i} ({} .. {} s): no fall", lean.t0, lean.t1));
        let (pitch, roll, _) = tilt(part[fall]);
        let towards = match direction_of[i] {
            0 => pitch,
            1 => -pitch,
            2 => -roll,
            _ => roll,
        };
        assert!(
            towards > 25.0,
            "{name}, lean {i}: fell pitch {pitch:.0} roll {roll:.0} deg"
        );
        let ankles: Vec<usize> = lean.ankles.iter().map(|a| col(&format!("q:{a}"))).collect();
        let angle = part[..fall]
            .iter()
            .map(|r| ankles.iter().map(|&c| r[c].abs()).sum::<f64>() / ankles.len() as f64)
            .fold(0.0, f64::max);
        out.push(angle.to_degrees());
    }
    out
}
