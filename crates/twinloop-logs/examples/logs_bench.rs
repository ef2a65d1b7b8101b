//! The log benchmark's two halves (bench/logs/bench.py drives them):
//!
//! `logs_bench write SECONDS FILE.mcap`: SECONDS of 1 kHz sensor_msgs/JointState for 20
//! joints (position, velocity, effort), zstd-chunked as the Python writer's default.
//! `logs_bench read FILE.mcap`: read it into a table as every command does, and print
//! `rows columns seconds` (wall time of `read_log`).
use std::path::Path;
use std::time::Instant;
use twinloop_logs::{McapLog, ReadOptions, read_log};

const JOINTS: usize = 20;

fn write(seconds: f64, path: &Path) -> Result<(), twinloop_logs::LogError> {
    let mut columns = vec!["t".to_string()];
    for p in ["q", "v", "tau"] {
        columns.extend((0..JOINTS).map(|j| format!("{p}:joint_{j:02}")));
    }
    let mut log = McapLog::create(path, &columns, None, "base_link")?;
    let mut row = vec![0.0; columns.len()];
    let n = (seconds * 1000.0).round() as usize;
    for k in 0..n {
        let t = k as f64 / 1000.0;
        row[0] = t;
        for j in 0..JOINTS {
            let w = 0.5 + 0.1 * j as f64;
            row[1 + j] = (w * t).sin();
            row[1 + JOINTS + j] = w * (w * t).cos();
            row[1 + 2 * JOINTS + j] = 0.01 * (j as f64) * (t * 3.0).sin();
        }
        log.write_row(&row)?;
    }
    log.finish()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: logs_bench write SECONDS FILE.mcap | logs_bench read FILE.mcap";
    let result = match args.get(1).map(String::as_str) {
        Some("write") if args.len() == 4 => {
            let seconds: f64 = args[2].parse().expect(usage);
            write(seconds, Path::new(&args[3]))
        }
        Some("read") if args.len() == 3 => {
            let start = Instant::now();
            read_log(Path::new(&args[2]), &ReadOptions::default()).map(|t| {
                let s = start.elapsed().as_secs_f64();
                println!("{} {} {s:.3}", t.rows.len(), t.columns.len());
            })
        }
        _ => {
            eprintln!("{usage}");
            std::process::exit(2);
        }
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}
