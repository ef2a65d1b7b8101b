//! Mutation fuzzing of the URDF reader with a deterministic PRNG: real files,
//! damaged thousands of ways, must give `Ok` or `Err` and never panic; whatever
//! reads must also survive a write/read round trip.

mod models_support;

use models_support::models_dir;
use std::panic::{AssertUnwindSafe, catch_unwind};
use twinloop_description::urdf;

/// xorshift64*: small, deterministic, good enough to pick mutations.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.max(1))
    }

    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }

    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Byte offsets of every occurrence of `pat` in `text`.
fn occurrences(text: &[u8], pat: &[u8]) -> Vec<usize> {
    if pat.is_empty() || text.len() < pat.len() {
        return Vec::new();
    }
    (0..=text.len() - pat.len())
        .filter(|&i| &text[i..i + pat.len()] == pat)
        .collect()
}

/// Replace one random occurrence of `from` with `to`; false if there is none.
fn replace_one(rng: &mut Rng, text: &mut Vec<u8>, from: &[u8], to: &[u8]) -> bool {
    let at = occurrences(text, from);
    if at.is_empty() {
        return false;
    }
    let i = *rng.pick(&at);
    text.splice(i..i + from.len(), to.iter().copied());
    true
}

/// Apply one random mutation.
pub fn mutate(rng: &mut Rng, text: &mut Vec<u8>) {
    let n = text.len().max(1);
    match rng.below(12) {
        // Truncate.
        0 => text.truncate(rng.below(n)),
        // Delete a range.
        1 => {
            let a = rng.below(n).min(text.len());
            let b = (a + 1 + rng.below(200)).min(text.len());
            text.drain(a..b);
        }
        // Duplicate a range somewhere else.
        2 => {
            let a = rng.below(n).min(text.len());
            let b = (a + 1 + rng.below(300)).min(text.len());
            let piece: Vec<u8> = text[a..b].to_vec();
            let at = rng.below(text.len() + 1);
            text.splice(at..at, piece);
        }
        // Insert random bytes, XML-ish and not.
        3 => {
            const ALPHABET: &[u8] = b"<>/=\"' \n\tabcxyz019.-+eE&;![]?:#\xc3\xa9\xff\x00";
            let at = rng.below(text.len() + 1);
            let len = 1 + rng.below(8);
            let bytes: Vec<u8> = (0..len).map(|_| *rng.pick(ALPHABET)).collect();
            text.splice(at..at, bytes);
        }
        // A digit becomes a letter, NaN, inf, or a huge number.
        4 => {
            let digits: Vec<usize> = (0..text.len())
                .filter(|&i| text[i].is_ascii_digit())
                .collect();
            if !digits.is_empty() {
                let i = *rng.pick(&digits);
                let choices: [&[u8]; 8] =
                    [b"x", b"NaN", b"inf", b"-inf", b"1e999", b"O", b" ", b""];
                let to = *rng.pick(&choices);
                text.splice(i..i + 1, to.iter().copied());
            }
        }
        // Swap tag names.
        5 => {
            let pairs: [(&[u8], &[u8]); 8] = [
                (b"<link", b"<joint"),
                (b"<joint", b"<link"),
                (b"</link>", b"</joint>"),
                (b"<origin", b"<axis"),
                (b"<inertial", b"<visual"),
                (b"<box", b"<sphere"),
                (b"<parent", b"<child"),
                (b"<mass", b"<inertia"),
            ];
            let (from, to) = *rng.pick(&pairs);
            replace_one(rng, text, from, to);
        }
        // Drop a closing tag.
        6 => {
            let closes = occurrences(text, b"</");
            if !closes.is_empty() {
                let a = *rng.pick(&closes);
                let b = text[a..]
                    .iter()
                    .position(|&c| c == b'>')
                    .map_or(text.len(), |p| a + p + 1);
                text.drain(a..b);
            }
        }
        // Unknown or other joint types.
        7 => {
            let choices: [&[u8]; 5] = [
                b"type=\"hinge\"",
                b"type=\"\"",
                b"type=\"fixed\"",
                b"type=\"floating\"",
                b"type=\"prismatic\"",
            ];
            let to = *rng.pick(&choices);
            let _ = replace_one(rng, text, b"type=\"revolute\"", to)
                || replace_one(rng, text, b"type=\"fixed\"", to);
        }
        // Drop an attribute name (required ones go missing).
        8 => {
            let names: [&[u8]; 6] = [
                b"name=",
                b"link=",
                b"xyz=",
                b"value=",
                b"ixx=",
                b"filename=",
            ];
            let from = *rng.pick(&names);
            replace_one(rng, text, from, b"nome=");
        }
        // Point a joint at another link name, or a missing one.
        9 => {
            replace_one(rng, text, b"link=\"", b"link=\"x");
        }
        // Change a separator in a list of numbers.
        10 => {
            replace_one(rng, text, b" 0 ", b" 0, ");
        }
        // Swap two random bytes.
        _ => {
            if text.len() >= 2 {
                let a = rng.below(text.len());
                let b = rng.below(text.len());
                text.swap(a, b);
            }
        }
    }
}

#[test]
fn mutated_urdfs_never_panic() {
    let files = [
        "op3/robotis_op3.nomesh.urdf",
        "op2/robotis_op2.nomesh.urdf",
        "unitree_h1/h1.nomesh.urdf",
        "coman/coman.nomesh.urdf",
        "darwin_op/robotis_op.nomesh.urdf",
        "unitree_g1/variants/g1_23dof_rev_1_0.nomesh.urdf",
    ];
    // 6 x 300 mutated files (each 1-3 mutations): about 4 s unoptimised, well under 1 s at the
    // workspace's test opt-level.
    let started = std::time::Instant::now();
    let mut rng = Rng::new(0x7717_1007_5eed_0001);
    let (mut ok, mut err) = (0usize, 0usize);
    for f in files {
        let original = std::fs::read(models_dir().join(f)).unwrap();
        for _ in 0..300 {
            let mut text = original.clone();
            for _ in 0..1 + rng.below(3) {
                mutate(&mut rng, &mut text);
            }
            let text = String::from_utf8_lossy(&text).into_owned();
            let outcome = catch_unwind(AssertUnwindSafe(|| {
                let result = urdf::from_str(&text);
                if let Ok(robot) = &result {
                    // What reads must write and read back the same, but for the notes on
                    // what the reader passed over: those name lines of the file read (the
                    // written one differs) and parts it dropped (not written again).
                    let without_notes = |r: &twinloop_description::Description| {
                        let mut r = r.clone();
                        r.unmodeled.clear();
                        r.ignored.clear();
                        r
                    };
                    let again = urdf::from_str(&urdf::to_string(robot)).map(|r| without_notes(&r));
                    assert!(
                        again == Ok(without_notes(robot)),
                        "round trip of an accepted mutation"
                    );
                }
                result.is_ok()
            }));
            match outcome {
                Ok(true) => ok += 1,
                Ok(false) => err += 1,
                Err(_) => {
                    let path = std::env::temp_dir().join("twinloop-urdf-fuzz-panic.urdf");
                    let _ = std::fs::write(&path, &text);
                    panic!(
                        "panic on a mutation of {f}; text saved to {}",
                        path.display()
                    );
                }
            }
        }
    }
    // The mutations must exercise both outcomes.
    assert!(ok > 100 && err > 100, "ok {ok}, err {err}");
    eprintln!("{ok} accepted, {err} rejected in {:?}", started.elapsed());
}

#[test]
fn every_prefix_of_a_small_urdf_is_handled() {
    let text = std::fs::read_to_string(models_dir().join("unitree_h1/h1.nomesh.urdf")).unwrap();
    let cut_points: Vec<usize> = (0..text.len())
        .step_by(41)
        .filter(|&i| text.is_char_boundary(i))
        .collect();
    for i in cut_points {
        let prefix = &text[..i];
        let r = catch_unwind(|| urdf::from_str(prefix).is_ok());
        assert_eq!(r.ok(), Some(false), "prefix of {i} bytes");
    }
}
