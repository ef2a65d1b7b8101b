use twinloop_report::{Plot, Report, SeriesStyle};

#[test]
fn report_is_self_contained_html_with_escaped_text() {
    let t: Vec<f64> = (0..1000).map(|k| k as f64 * 0.01).collect();
    let y: Vec<f64> = t.iter().map(|t| t.sin()).collect();
    let plot = Plot::new("sine <test>", "t (s)", "y")
        .line("sin", &t, &y)
        .hline(0.5, "band");
    let bars = Plot::new("hsv", "order", "value")
        .series(
            "hsv",
            &[1.0, 2.0, 3.0],
            &[10.0, 1.0, 0.01],
            SeriesStyle::Bars,
        )
        .log_y();
    let mut r = Report::new("A & B");
    r.heading("Section").paragraph("x < y").table(
        vec!["a".into(), "b".into()],
        vec![vec!["1".into(), "2".into()]],
    );
    r.plot(&plot).plot(&bars);
    let html = r.to_html();
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert!(html.contains("<title>A &amp; B</title>"));
    assert!(html.contains("x &lt; y"));
    assert!(html.contains("sine &lt;test&gt;"));
    assert_eq!(html.matches("<svg").count(), 2);
    assert!(!html.contains("<script"), "no JavaScript");
    assert!(!html.contains("NaN"), "no non-finite coordinates");
    // The sine has 1000 points; the path must hold them or a thinned subset.
    let path_len = html
        .split("<path d=\"")
        .nth(1)
        .unwrap()
        .split('"')
        .next()
        .unwrap()
        .matches('L')
        .count();
    assert!(path_len > 100 && path_len < 1000);
}

#[test]
fn degenerate_data_does_not_break_the_plot() {
    let p = Plot::new("empty", "x", "y").line("none", &[], &[]).line(
        "nan",
        &[f64::NAN, 1.0],
        &[1.0, f64::INFINITY],
    );
    let svg = p.to_svg();
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
    let flat = Plot::new("flat", "x", "y")
        .line("c", &[0.0, 1.0], &[2.0, 2.0])
        .to_svg();
    assert!(!flat.contains("NaN"));
}

#[test]
fn a_link_is_an_anchor_with_its_text_and_target_escaped() {
    let mut r = Report::new("t");
    r.link("open <replay>", "replay \"1\".html");
    let html = r.to_html();
    assert!(
        html.contains("<p><a href=\"replay &quot;1&quot;.html\">open &lt;replay&gt;</a></p>"),
        "{html}"
    );
}

/// A view drawn to scale (issue 30 item 10: the adaptation report's side view was
/// stretched): a unit step on x and on y are as many pixels apart.
#[test]
fn an_equal_aspect_plot_draws_x_and_y_to_the_same_scale() {
    let svg = Plot::new("side view", "x, m", "z, m")
        .equal_aspect()
        .height(480.0)
        .series(
            "points",
            &[0.0, 0.1, 0.0],
            &[0.0, 0.0, 0.1],
            SeriesStyle::Points,
        )
        .to_svg();
    let centres: Vec<(f64, f64)> = svg
        .split("<circle cx=\"")
        .skip(1)
        .map(|c| {
            let cx: f64 = c.split('"').next().unwrap().parse().unwrap();
            let cy: f64 = c
                .split("cy=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap()
                .parse()
                .unwrap();
            (cx, cy)
        })
        .collect();
    assert!(centres.len() >= 3, "{svg}");
    let across = (centres[1].0 - centres[0].0).abs();
    let up = (centres[2].1 - centres[0].1).abs();
    assert!(across > 10.0, "{centres:?}");
    assert!(
        (across - up).abs() <= 0.2,
        "x step {across} px, y step {up} px"
    );
}
