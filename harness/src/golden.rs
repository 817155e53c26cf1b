//! Golden trace files: one per scenario, `golden/<scenario>.snap`.
//!
//! The files are insta snapshots (so `cargo insta review` accepts a changed
//! emulator trace), which is a short `---` header and the trace text.
//! Nothing here overwrites a file unless asked; reads and writes go through
//! [`crate::files`], so an interrupted write never leaves half a golden
//! file and a FIFO or a huge file is refused, not read.

use crate::compare::{compare_graded, Tolerances};
use crate::files::{self, FileError, MAX_TRACE_BYTES};
use crate::protocol::Straps;
use crate::scenario::{
    deviation_of, Failure, Grade, HarnessError, Measurement, ScenarioResult, Verdict,
};
use crate::trace::{Trace, TraceError};
use ppmc_record::Reference;
use std::path::{Path, PathBuf};

/// The front matter `ppmc record` writes: insta's, as the golden files
/// carry it from when the golden check was `harness/tests/golden.rs`
/// (it is now `harness/tests/it/golden.rs`, and `cargo insta review`
/// writes that). A file whose trace is the same is the same golden file
/// whatever its front matter ([`write()`] leaves it unchanged).
pub const SNAPSHOT_HEADER: &str = "---\nsource: harness/tests/golden.rs\n---\n";

/// `text` without insta's front matter (`---` ... `---`), if it has one.
fn without_front_matter(text: &str) -> &str {
    text.strip_prefix("---\n")
        .and_then(|rest| rest.split_once("\n---\n"))
        .map_or(text, |(_, trace)| trace)
}

/// A golden file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum GoldenError {
    /// No golden file for the scenario.
    #[error(
        "{path}: no golden trace for this scenario (record one with `{} record`)",
        crate::program()
    )]
    Missing { path: PathBuf },
    /// The file could not be read or written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The file is not a valid trace (corrupt, truncated, another version).
    #[error("{path}:{line}: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// The file is a trace of another scenario.
    #[error("{path}:2: this is the trace of scenario `{found}`, not `{expected}`")]
    WrongScenario {
        path: PathBuf,
        expected: String,
        found: String,
    },
    /// The file was recorded on a chip strapped otherwise than the one it
    /// would judge: every time in it would be off for that reason alone.
    #[error("{path}: recorded at {recorded}, but the target is strapped {target}; record golden traces at these straps (`{} record`) or judge a board strapped as they were", crate::program())]
    OtherStraps {
        path: PathBuf,
        recorded: Straps,
        target: Straps,
    },
    /// Writing would replace an existing golden file.
    #[error("{path}: exists; pass --bless to replace golden files")]
    Exists { path: PathBuf },
}

/// The file for `scenario` in `dir`: `<scenario>.snap`, or `<scenario>.trace`
/// when only that exists (a trace set saved by `--artifacts`).
pub fn path_for(dir: &Path, scenario: &str) -> PathBuf {
    let snap = dir.join(format!("{scenario}.snap"));
    let trace = dir.join(format!("{scenario}.trace"));
    if !snap.exists() && trace.exists() {
        trace
    } else {
        snap
    }
}

/// Reads and checks the golden trace of `scenario`.
pub fn load(dir: &Path, scenario: &str) -> Result<Trace, GoldenError> {
    let path = path_for(dir, scenario);
    let text = match files::read_text(&path, MAX_TRACE_BYTES) {
        Ok(t) => t,
        Err(e) if e.is_not_found() => return Err(GoldenError::Missing { path }),
        Err(e) => return Err(e.into()),
    };
    let trace = Trace::parse(&text).map_err(|TraceError { line, message }| GoldenError::Parse {
        path: path.clone(),
        line,
        message,
    })?;
    if trace.scenario != scenario {
        return Err(GoldenError::WrongScenario {
            path,
            expected: scenario.to_string(),
            found: trace.scenario,
        });
    }
    Ok(trace)
}

/// Reads the golden trace of `scenario` to judge a target strapped
/// `straps`: one recorded at other straps is refused by name.
pub fn load_for(dir: &Path, scenario: &str, straps: &Straps) -> Result<Trace, GoldenError> {
    let trace = load(dir, scenario)?;
    if trace.straps != *straps {
        return Err(GoldenError::OtherStraps {
            path: path_for(dir, scenario),
            recorded: trace.straps,
            target: *straps,
        });
    }
    Ok(trace)
}

/// What [`write()`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Written {
    Created,
    Replaced,
    Unchanged,
}

/// Writes `trace` as the golden file of its scenario in `dir`. An existing
/// file with other content is replaced only with `bless` (atomically, by a
/// rename). A new file is created exclusively: of two recorders into one
/// folder, the second finds the first's file and says `Unchanged` or
/// [`GoldenError::Exists`], never replaces it silently.
pub fn write(dir: &Path, trace: &Trace, bless: bool) -> Result<Written, GoldenError> {
    let path = dir.join(format!("{}.snap", trace.scenario));
    let text = format!("{SNAPSHOT_HEADER}{}", trace.render());
    // Once more if another process creates the file between the look and
    // the creation: the second look sees its file.
    for _ in 0..2 {
        // A symlink or a FIFO at the name is refused before it is read.
        files::check_replaceable(&path)?;
        let existing = match files::read_text(&path, MAX_TRACE_BYTES) {
            Ok(t) => Some(t),
            Err(e) if e.is_not_found() => None,
            Err(e) => return Err(e.into()),
        };
        match existing {
            Some(t) if without_front_matter(&t) == without_front_matter(&text) => {
                return Ok(Written::Unchanged)
            }
            Some(_) if !bless => return Err(GoldenError::Exists { path }),
            Some(_) => {
                files::write(&path, text.as_bytes())?;
                return Ok(Written::Replaced);
            }
            None => match files::create_new(&path, text.as_bytes()) {
                Ok(()) => return Ok(Written::Created),
                Err(FileError::Exists { .. }) => continue,
                Err(e) => return Err(e.into()),
            },
        }
    }
    Err(GoldenError::Exists { path })
}

/// The golden verdict rule, the one every command applies: `r`'s trace
/// compared with its golden trace in `dir` within `tol`
/// ([`compare_graded`]). A divergence fails the scenario (the device); a
/// comparison within the instruments' uncertainty of its limit makes a
/// pass MARGINAL, kept as a measurement; a missing, corrupt or mismatched
/// golden file, or no capture to compare, is an error of the harness's
/// input, never the device's. A result that did not pass is not compared.
/// Returns the golden trace compared with, for a report to draw.
pub fn check(r: &mut ScenarioResult, dir: &Path, tol: &Tolerances) -> Option<Trace> {
    if !r.verdict.ok() {
        // Not compared, but drawn beside the board's all the same.
        let straps = &r.trace.as_ref()?.straps;
        return load_for(dir, r.name, straps).ok();
    }
    let Some(trace) = &r.trace else {
        r.verdict = Verdict::Error(HarnessError::Golden(
            "no capture to compare with the golden trace".into(),
        ));
        return None;
    };
    let fail = |expectation: String, expected: String, got: String, at, deviation| {
        Verdict::Failed(Failure {
            expectation,
            expected,
            got,
            at,
            deviation,
        })
    };
    match load_for(dir, r.name, &trace.straps) {
        Ok(g) => {
            match compare_graded(&g, trace, tol) {
                Err(d) => {
                    let deviation = deviation_of(&d.golden, &d.got, Reference::Golden);
                    r.verdict = fail(
                        format!("golden trace: first divergence in {}", d.quantity),
                        format!("{} (allowed {})", d.golden, d.allowed),
                        d.got,
                        d.at,
                        deviation,
                    );
                }
                // Within the instruments' uncertainty of a limit: the
                // first such comparison, graded as a measurement is.
                Ok(graded) => {
                    if let Some(m) = graded.first {
                        r.measurements.push(Measurement {
                            name: format!("golden trace: {}", m.quantity),
                            value: m.got,
                            lo: m.lo,
                            hi: m.hi,
                            marginal_lo: m.lo,
                            marginal_hi: m.hi,
                            u: m.u,
                            grade: Grade::Marginal,
                            at: m.at,
                        });
                        if r.verdict == Verdict::Passed {
                            r.verdict = Verdict::Marginal;
                        }
                    }
                }
            }
            Some(g)
        }
        // A missing, corrupt or mismatched golden file is the harness's
        // input at fault, never the device.
        Err(e) => {
            r.verdict = Verdict::Error(HarnessError::Golden(e.to_string()));
            None
        }
    }
}

/// The trace to record from `r`, or why not. Only a complete run is ever a
/// reference: a scenario that ended in a harness or link error, or never
/// ran, has an incomplete capture whatever the flags; a device failure is
/// admitted with `--allow-failures` only.
pub fn admit(r: &ScenarioResult, allow_failures: bool) -> Result<&Trace, String> {
    match (&r.verdict, &r.trace) {
        (Verdict::Error(e), _) => Err(format!(
            "not recorded: it ended in an error, so its capture is incomplete ({e})"
        )),
        (Verdict::NotRun(why), _) => Err(format!("not recorded: it did not run ({why})")),
        (Verdict::Failed(_), Some(_)) if !allow_failures => Err(format!(
            "not recorded: the device failed it ({}); fix it or pass --allow-failures",
            r.verdict.detail().unwrap_or_default()
        )),
        (_, None) => Err("not recorded: the target gave no capture".into()),
        (Verdict::Passed | Verdict::Marginal | Verdict::Failed(_), Some(t)) => Ok(t),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    use crate::files::scratch;

    fn trace(name: &str) -> Trace {
        Trace::parse(&format!(
            "ppmc-trace 1\nscenario {name}\nsection 3-1\ntarget emu\ndetail sysclk_hz 16000000\ndetail csel high\ndetail vsel high\ndetail ext_clock_hz none\nevents\n0.000us reset\nend\n"
        ))
        .expect("valid")
    }

    #[test]
    fn write_never_overwrites_without_bless() {
        let dir = scratch("golden");
        let d = dir.path();
        assert_eq!(write(d, &trace("a"), false).expect("new"), Written::Created);
        assert_eq!(
            write(d, &trace("a"), false).expect("same"),
            Written::Unchanged
        );
        let mut other = trace("a");
        other.section = "3-2".into();
        let before = fs::read_to_string(d.join("a.snap")).expect("exists");
        assert!(matches!(
            write(d, &other, false),
            Err(GoldenError::Exists { .. })
        ));
        assert_eq!(fs::read_to_string(d.join("a.snap")).expect("kept"), before);
        assert_eq!(write(d, &other, true).expect("blessed"), Written::Replaced);
        assert_eq!(load(d, "a").expect("loads"), other);
        let leftovers: Vec<_> = fs::read_dir(d)
            .expect("dir")
            .filter_map(Result::ok)
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
            .collect();
        assert!(leftovers.is_empty());
    }

    /// A golden file that `cargo insta review` wrote (its front matter
    /// naming the check where it is now) holds the same trace: recording
    /// it again leaves it as it is.
    #[test]
    fn a_file_with_other_front_matter_and_the_same_trace_is_unchanged() {
        let dir = scratch("golden");
        let d = dir.path();
        let t = trace("a");
        let insta = format!(
            "---\nsource: harness/tests/it/golden.rs\n---\n{}",
            t.render()
        );
        fs::write(d.join("a.snap"), &insta).expect("written");
        assert_eq!(write(d, &t, false).expect("same trace"), Written::Unchanged);
        assert_eq!(fs::read_to_string(d.join("a.snap")).expect("kept"), insta);
        let mut other = t.clone();
        other.section = "3-2".into();
        assert!(matches!(
            write(d, &other, false),
            Err(GoldenError::Exists { .. })
        ));
    }

    /// Writers racing for the same new files: each file is created by
    /// exactly one, and every other writer sees it (unchanged when its
    /// trace is the same, refused when not); no file is replaced.
    #[test]
    fn racing_writers_create_each_file_once_and_never_replace_it() {
        let dir = scratch("golden");
        let d = dir.path();
        let names: Vec<String> = (0..40).map(|i| format!("s{i}")).collect();
        // Writers 0 and 1 write the same traces, 2 and 3 other ones.
        let results: Vec<Vec<&str>> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..4)
                .map(|w| {
                    let names = &names;
                    scope.spawn(move || {
                        names
                            .iter()
                            .map(|n| {
                                let mut t = trace(n);
                                if w >= 2 {
                                    t.section = "3-2".into();
                                }
                                match write(d, &t, false) {
                                    Ok(Written::Created) => "created",
                                    Ok(Written::Unchanged) => "unchanged",
                                    Ok(Written::Replaced) => "replaced",
                                    Err(GoldenError::Exists { .. }) => "refused",
                                    Err(e) => panic!("{e}"),
                                }
                            })
                            .collect()
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("writer"))
                .collect()
        });
        for (i, n) in names.iter().enumerate() {
            let outcomes: Vec<&str> = results.iter().map(|r| r[i]).collect();
            let created: Vec<usize> = (0..4).filter(|w| outcomes[*w] == "created").collect();
            assert_eq!(created.len(), 1, "{n}: {outcomes:?}");
            // The file is the creator's; each other writer saw it as it is.
            let winner = created[0] >= 2;
            let on_disk = load(d, n).expect("loads").section == "3-2";
            assert_eq!(on_disk, winner, "{n}: {outcomes:?}");
            for w in (0..4).filter(|w| *w != created[0]) {
                let same = (w >= 2) == winner;
                let want = if same { "unchanged" } else { "refused" };
                assert_eq!(outcomes[w], want, "{n}: writer {w}: {outcomes:?}");
            }
        }
        let leftovers = fs::read_dir(d)
            .expect("dir")
            .filter_map(Result::ok)
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
            .count();
        assert_eq!(leftovers, 0);
    }

    #[test]
    fn bad_golden_files_name_path_and_line() {
        let dir = scratch("golden");
        let d = dir.path();
        assert!(matches!(load(d, "x"), Err(GoldenError::Missing { .. })));
        fs::write(d.join("x.snap"), format!("{SNAPSHOT_HEADER}ppmc-trace 1\nscenario x\nsection 3\ntarget emu\ndetail sysclk_hz 16000000\ndetail csel high\ndetail vsel high\ndetail ext_clock_hz none\nevents\n0.000us bogus\nend\n")).expect("write");
        let e = load(d, "x").expect_err("corrupt");
        assert!(
            e.to_string().ends_with("x.snap:13: unknown event `bogus`"),
            "{e}"
        );
        fs::write(d.join("y.snap"), trace("x").render()).expect("write");
        let e = load(d, "y").expect_err("other scenario");
        assert!(
            e.to_string().contains("trace of scenario `x`, not `y`"),
            "{e}"
        );
        let at12 = Straps {
            sysclk_hz: 12_000_000,
            ..Straps::default()
        };
        write(d, &trace("w"), false).expect("new");
        let e = load_for(d, "w", &at12).expect_err("other straps");
        assert!(
            e.to_string().contains(
                "w.snap: recorded at SysClk 16 MHz, CSEL high, VSEL high, no external clock, but the target is strapped SysClk 12 MHz"
            ),
            "{e}"
        );
        assert!(load_for(d, "w", &Straps::default()).is_ok());
        fs::write(d.join("z.snap"), "ppmc-trace 1\nscenario z\n").expect("write");
        assert!(load(d, "z")
            .expect_err("truncated")
            .to_string()
            .contains("truncated"));
    }
}

#[cfg(test)]
mod admit_tests {
    use super::*;
    use crate::backend::TargetErrorKind;
    use crate::scenario::{Failure, HarnessError, NotRun};
    use crate::time::{Duration, Instant};

    fn result(verdict: Verdict, trace: bool) -> ScenarioResult {
        let text = "ppmc-trace 1\nscenario x\nsection 3-1\ntarget emu\ndetail sysclk_hz 16000000\n\
                    detail csel high\ndetail vsel high\ndetail ext_clock_hz none\nevents\n0.000us reset\nend\n";
        ScenarioResult {
            name: "x",
            section: "3-1",
            tags: &[],
            verdict,
            measurements: Vec::new(),
            trace: trace.then(|| Trace::parse(text).expect("valid trace")),
            elapsed: Duration::ZERO,
            wall: std::time::Duration::ZERO,
            attempts: Vec::new(),
        }
    }

    fn failed() -> Verdict {
        Verdict::Failed(Failure {
            expectation: "finish status".into(),
            expected: "0x8E".into(),
            got: "0x00".into(),
            at: Instant::ZERO,
            deviation: None,
        })
    }

    #[test]
    fn only_complete_runs_become_golden_traces() {
        let link = Verdict::Error(HarnessError::Target {
            kind: TargetErrorKind::Link,
            message: "no reply".into(),
        });
        for allow in [false, true] {
            let e = admit(&result(link.clone(), true), allow).expect_err("error refused");
            assert!(e.contains("capture is incomplete"), "{e}");
            let lost = Verdict::NotRun(NotRun::TargetLost("gone".into()));
            assert!(admit(&result(lost, true), allow).is_err());
            assert!(admit(&result(Verdict::Passed, false), allow).is_err());
            assert!(admit(&result(Verdict::Passed, true), allow).is_ok());
            assert!(admit(&result(Verdict::Marginal, true), allow).is_ok());
        }
        let e = admit(&result(failed(), true), false).expect_err("failure refused");
        assert!(e.contains("--allow-failures"), "{e}");
        assert!(admit(&result(failed(), true), true).is_ok());
    }
}
