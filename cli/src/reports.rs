//! A command's reports of its run record: the outputs tried before the
//! work (`--junit`, `--json`, `--html`, `--store`), and written from the
//! one record after it.

use crate::{usage, CliError};
use files::kind::Kind;
use ppmc_files as files;
use ppmc_record::RunRecord;
use ppmc_report as report;
use ppmc_report::store::{Added, Location, Store};
use std::path::Path;

/// Where a command writes its record: each report, if asked for.
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct Outputs<'a> {
    pub junit: Option<&'a Path>,
    pub json: Option<&'a Path>,
    pub html: Option<&'a Path>,
}

/// Writes `record` to every output asked for and keeps it in `store`;
/// returns what could not be written, each naming where and why (one
/// report that fails does not keep the others from being written).
pub(super) fn write(record: &RunRecord, to: Outputs, store: Option<&mut Store>) -> Vec<String> {
    let mut problems = Vec::new();
    let mut put = |path: &Path, text: Result<String, String>| {
        let done = text
            .map_err(|e| format!("{}: {e}", path.display()))
            .and_then(|t| files::write_report(path, t.as_bytes()).map_err(|e| e.to_string()));
        let ok = done.is_ok();
        problems.extend(done.err());
        ok
    };
    if let Some(p) = to.junit {
        let _ = put(p, Ok(report::junit(record)));
    }
    // The JSON record, where it was written: a store's fallback.
    let json = to.json.filter(|p| {
        put(
            p,
            record
                .to_json()
                .map_err(|e| format!("cannot render the JSON run record: {e}")),
        )
    });
    if let Some(p) = to.html {
        let _ = put(
            p,
            Ok(report::html(
                std::slice::from_ref(record),
                match record.run.source {
                    Some(_) => "ppmc judge report",
                    None => "ppmc run report",
                },
            )),
        );
    }
    if let Some(store) = store {
        match store.add(record) {
            Ok(Added::New(_)) => {}
            Ok(Added::Already) => problems.push(format!(
                "--store {}: this run is in the store already (its id {}): kept once",
                store.shown(),
                record.run.id.as_deref().unwrap_or("(none)")
            )),
            Err(e) => problems.push(crate::store::unsent(record, json, &e)),
        }
    }
    problems
}

/// Tries the `--junit` and `--json` outputs before the work, rather than
/// finding them unusable after it: each writable, not the same file, at
/// most one on standard output (the verdict lines then go to standard
/// error).
pub(super) fn prepare_reports(
    junit: Option<&Path>,
    json: Option<&Path>,
    html: Option<&Path>,
    store: Option<&Path>,
) -> Result<(), CliError> {
    if store.is_some_and(|s| s.as_os_str() == "-") {
        return Err(usage(
            "--store -: a results store is a file or a postgres:// URL, not standard output",
        ));
    }
    // A store on a server is no file to weigh against the reports.
    let store = match store.map(Location::of).transpose() {
        Ok(Some(Location::Server(_))) | Ok(None) => None,
        Ok(Some(Location::File(_))) => store,
        Err(why) => return Err(usage(format!("--store {why}"))),
    };
    // The store is told apart from the reports too: a report written over
    // it would replace a lab's history.
    let named = [
        ("--junit", junit),
        ("--json", json),
        ("--html", html),
        ("--store", store),
    ];
    let reports: Vec<(&str, &Path)> = named
        .into_iter()
        .filter_map(|(flag, p)| p.map(|p| (flag, p)))
        .collect();
    for (_, report) in &reports {
        files::check_writable(report)?;
    }
    for (i, (a, pa)) in reports.iter().enumerate() {
        for (b, pb) in &reports[i + 1..] {
            if files::same_file(pa, pb) {
                return Err(usage(format!(
                    "{a} {} and {b} {} are the same file: give each report its own",
                    pa.display(),
                    pb.display()
                )));
            }
        }
    }
    // A report replaces only a report of its kind (or an empty file).
    let kinds = [(Kind::Junit, junit), (Kind::Json, json), (Kind::Html, html)];
    for ((flag, _), (kind, path)) in named.iter().zip(kinds) {
        if let Some(path) = path.filter(|p| p.as_os_str() != "-") {
            files::kind::may_replace(path, kind).map_err(|e| usage(format!("{flag} {e}")))?;
        }
    }
    let on_stdout: Vec<&str> = reports
        .iter()
        .filter(|(_, p)| p.as_os_str() == "-")
        .map(|(flag, _)| *flag)
        .collect();
    match on_stdout.len() {
        0 => Ok(()),
        // Standard output carries the report: the verdicts go to stderr.
        1 => {
            super::out::people_to_stderr();
            Ok(())
        }
        _ => Err(usage(format!(
            "{} - cannot both take standard output",
            on_stdout.join(" - and ")
        ))),
    }
}
