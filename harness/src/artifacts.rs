//! What a run keeps of a scenario that did not pass (`--artifacts`): its
//! trace, and a VCD of its waveform around the failure.

use crate::files;
use crate::scenario::{ScenarioResult, Verdict};
use crate::time::{Duration, Instant};
use std::path::Path;

/// How much of a failed scenario's waveform to keep.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Window {
    /// The whole trace.
    All,
    /// This long before and after the failure.
    Around(Duration),
}

/// Saves `r`'s trace and VCD in `dir`, adding each file written to `saved`
/// (for the reports to point at; a file written before a later one failed
/// is listed all the same). The VCD covers `window` either side of the
/// failure, when there is one; a scenario that ended in an error has no
/// failure time, and its VCD is whole. Each error names the file.
pub fn save(
    dir: &Path,
    r: &ScenarioResult,
    window: Window,
    saved: &mut Vec<String>,
) -> Result<(), String> {
    let Some(trace) = &r.trace else { return Ok(()) };
    let text = trace.render();
    let tpath = dir.join(format!("{}.trace", r.name));
    files::write(&tpath, text.as_bytes()).map_err(|e| e.to_string())?;
    saved.push(tpath.display().to_string());
    let vpath = dir.join(format!("{}.vcd", r.name));
    let around = match (&r.verdict, window) {
        (Verdict::Failed(f), Window::Around(d)) => {
            let from = Instant::from_nanos(f.at.as_nanos().saturating_sub(d.as_nanos()));
            Some((from, f.at + d))
        }
        _ => None,
    };
    files::write_with(&vpath, |w| {
        crate::vcd_export::export_window(trace, around, w)
    })
    .map_err(|e| e.to_string())?;
    saved.push(vpath.display().to_string());
    Ok(())
}

/// A board's label as a folder name: `serial:/dev/ttyACM0` becomes
/// `serial__dev_ttyACM0`.
pub fn folder_name(label: &str) -> String {
    label
        .chars()
        .map(|c| match c {
            'a'..='z' | 'A'..='Z' | '0'..='9' | '-' | '.' | '#' => c,
            _ => '_',
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_board_label_becomes_one_folder_name() {
        assert_eq!(folder_name("serial:/dev/ttyACM0"), "serial__dev_ttyACM0");
        assert_eq!(folder_name("rfc2217://lab:2001"), "rfc2217___lab_2001");
        assert_eq!(folder_name("../x"), ".._x");
    }
}
