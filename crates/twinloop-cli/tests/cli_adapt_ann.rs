//! `twinloop adapt train` and `twinloop adapt --method ann` through the binary: a small
//! network trained on simulated changes of km20, then used on the simulated tip-over of
//! a km20 with a hidden 0.3 kg on its torso; bad input named, exit 2.

use std::process::Command;

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-cli-ann-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn twinloop(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(args)
        .output()
        .unwrap()
}

fn ok(args: &[&str]) -> String {
    let o = twinloop(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn fails_naming(args: &[&str], what: &str) {
    let o = twinloop(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(err.contains(what), "{args:?}: {err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

#[test]
fn train_then_adapt_with_the_network() {
    let net = tmp("net.json");
    let net_s = net.to_str().unwrap();
    let json = tmp("train.json");
    let html = tmp("train.html");
    let text = ok(&[
        "adapt",
        "train",
        "--robot",
        "builtin:km20",
        "--samples",
        "1500",
        "--seed",
        "3",
        "--out",
        net_s,
        "--json",
        json.to_str().unwrap(),
        "--report",
        html.to_str().unwrap(),
    ]);
    eprintln!("{text}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(r["split"], serde_json::json!([1050, 225, 225]));
    assert_eq!(r["layout"], serde_json::json!([9, 5, 10, 5, 9]));
    let methods = r["validation"]["methods"].as_array().unwrap();
    let com = |k: usize| methods[k]["com_mm"][0].as_f64().unwrap();
    assert!(methods[2]["method"].as_str().unwrap().starts_with("ANN"));
    assert!(com(2) < com(1), "ANN {} mm, manual {} mm", com(2), com(1));
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("Table VII") && page.contains("<svg"));

    // The hidden change, measured by the simulated tip-over.
    let tip = tmp("tip.json");
    let tip_s = tip.to_str().unwrap();
    ok(&[
        "experiment",
        "tipover",
        "--robot",
        "builtin:km20",
        "--add-mass",
        "0.3@torso:0.04,0.02,0.05",
        "--json",
        tip_s,
    ]);
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&tip).unwrap()).unwrap();
    let out = ok(&[
        "adapt",
        "--robot",
        "builtin:km20",
        "--tipover",
        tip_s,
        "--method",
        "ann",
        "--net",
        net_s,
        "--where",
        "torso",
        "--total-mass",
        "3.636",
        "--json",
        "-",
    ]);
    let a: serde_json::Value = serde_json::from_str(&out).unwrap();
    let truth: Vec<f64> = (0..3)
        .map(|k| t["com"]["true"][k].as_f64().unwrap())
        .collect();
    let vcom: Vec<f64> = (0..3)
        .map(|k| a["adapted_com"][k].as_f64().unwrap())
        .collect();
    let err: Vec<f64> = (0..3).map(|k| (vcom[k] - truth[k]).abs()).collect();
    eprintln!("ANN vCoM {vcom:?} truth {truth:?}: {err:?} m; {out}");
    // One change through a small network (its statistics are the library test's): x
    // and z follow from the forward and backward angles, the network's inputs; y does
    // not (the left and right angles are not inputs): only the part and the mass tell
    // it, so it is the mean y of such changes.
    assert!(err[0] < 5e-3 && err[2] < 5e-3, "{err:?}");
    assert!(err[1] < 6e-3, "{err:?}");
    assert_eq!(a["part"], "torso");
    for (k, d) in ["forward", "backward"].iter().enumerate() {
        let measured = t[d]["measured_deg"].as_f64().unwrap();
        let model = a["adapted_fall_deg"][k].as_f64().unwrap();
        assert!((measured - model).abs() < 1.0, "{d}: {measured} vs {model}");
    }

    let base = [
        "adapt",
        "--robot",
        "builtin:km20",
        "--tipover",
        tip_s,
        "--method",
        "ann",
    ];
    let with = |extra: &[&'static str]| -> Vec<&str> {
        let mut v: Vec<&str> = base.to_vec();
        v.extend(extra);
        v
    };
    fails_naming(&with(&["--where", "torso"]), "--net");
    let mut v = with(&["--total-mass", "3.636"]);
    v.extend(["--net", net_s]);
    fails_naming(&v, "--where");
    let mut v = with(&["--where", "torso", "--total-mass", "3.636"]);
    v.extend(["--net", tip_s]);
    fails_naming(&v, "--net");
    let mut v = with(&["--where", "torso"]);
    v.extend(["--net", net_s]);
    fails_naming(&v, "total");
    fails_naming(
        &[
            "adapt",
            "train",
            "--robot",
            "builtin:km20",
            "--samples",
            "100",
            "--mass-range",
            "0.5",
            "--out",
            net_s,
        ],
        "--mass-range",
    );
}
