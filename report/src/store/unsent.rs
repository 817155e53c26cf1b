//! A run's record that its store did not take (the server out of reach, a
//! trigger of the lab's refusing it) is kept on disk for `ppmc store
//! push`: nothing a run learned is lost to a store.

use ppmc_record::RunRecord;
use std::path::{Path, PathBuf};

/// Where the record of a run its store did not take is kept: the `--json`
/// record `json`, where it went to a file; else a file of its own in the
/// working folder, `ppmc-unsent-RUNID.json`, never over another file.
/// `Err` says why it could not be kept either.
pub fn keep_unsent(record: &RunRecord, json: Option<&Path>) -> Result<PathBuf, String> {
    if let Some(p) = json.filter(|p| p.as_os_str() != "-") {
        return Ok(p.to_path_buf());
    }
    let id = record.run.id.as_deref().unwrap_or("run");
    let path = PathBuf::from(format!("ppmc-unsent-{id}.json"));
    let text = record.to_json().map_err(|e| e.to_string())?;
    ppmc_files::create_new(&path, text.as_bytes()).map_err(|e| e.to_string())?;
    Ok(path)
}
