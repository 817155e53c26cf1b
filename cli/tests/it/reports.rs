//! The reports as their consumers read them: the JSON record against its
//! schema (`docs/run-record.schema.json`), and the JUnit file against the
//! rules of the Jenkins xunit schema (`junit-10.xsd`) that GitLab and
//! junitparser also accept. CI feeds the same files to junitparser.

use crate::common;

use common::{check_record as check, ppmc, run_record_schema as schema, scratch, text};
use std::path::Path;

/// Real records of every verdict kind: passed and marginal (the emulator),
/// failed and error (a board fault, a corrupt golden file behind the
/// bridge-less emulator), not run (an unreachable target).
#[test]
fn real_run_records_match_the_schema_and_spell_each_verdict_once() {
    let validator = schema();
    let dir = scratch("reports");
    let json = dir.path().join("run.json");
    let j = json.to_str().expect("utf-8");
    let out = ppmc(&["run", "--json", j, "--shard", "1/3", "--skip-tag", "long"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("JSON");
    check(&validator, &record);
    assert_eq!(record["run"]["options"]["shard"], "1/3");
    assert_eq!(record["run"]["options"]["skip_tags"][0], "long");

    // A failure with expected and got as fields.
    let golden = dir.path().join("golden");
    std::fs::create_dir(&golden).expect("dir");
    let out = ppmc(&[
        "run",
        "--json",
        j,
        "--filter",
        "e0_undefined",
        "--golden",
        golden.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("JSON");
    check(&validator, &record);
    assert_eq!(record["scenarios"][0]["verdict"], "error");
    assert_eq!(record["scenarios"][0]["error"]["kind"], "harness");
    assert_eq!(record["summary"]["error"], 1);

    let out = ppmc(&[
        "run",
        "--json",
        j,
        "--filter",
        "e0_undefined",
        "--target",
        "serial:/dev/ppmc-no-such-port",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("JSON");
    check(&validator, &record);
    assert_eq!(record["scenarios"][0]["verdict"], "not_run");
    assert_eq!(record["summary"]["not_run"], 1);
    assert_eq!(record["scenarios"][0]["error"]["kind"], "infrastructure");
}

/// A golden trace 3 % slower than the emulator: a divergence the device is
/// blamed for, with expected and got as fields.
#[test]
fn a_device_failure_carries_expected_and_got_as_fields() {
    let validator = schema();
    let dir = scratch("reports");
    let golden = dir.path().join("golden");
    std::fs::create_dir(&golden).expect("dir");
    let name = "s3_3_5_constant_speed_100_steps";
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../golden/{name}.snap"));
    let trace =
        ppmc::trace::Trace::parse(&std::fs::read_to_string(src).expect("golden")).expect("parses");
    let slower = ppmc::compare::scale_times(&trace, 103, 100);
    std::fs::write(golden.join(format!("{name}.snap")), slower.render()).expect("write");
    let json = dir.path().join("run.json");
    let out = ppmc(&[
        "run",
        "--json",
        json.to_str().expect("utf-8"),
        "--filter",
        name,
        "--golden",
        golden.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("JSON");
    check(&validator, &record);
    let s = &record["scenarios"][0];
    assert_eq!(s["verdict"], "failed");
    assert_eq!(record["summary"]["failed"], 1);
    assert!(s["failure"]["expected"].is_string(), "{s}");
    assert!(s["failure"]["got"].is_string(), "{s}");
    assert!(s["error"].is_null(), "{s}");
}

/// The attributes and children `junit-10.xsd` allows, checked on a real
/// report with a failure, an error, repeats, a shard and attachments.
#[test]
fn the_junit_report_keeps_the_jenkins_schema_rules() {
    let dir = scratch("reports");
    let junit = dir.path().join("r.xml");
    let arts = dir.path().join("arts");
    let golden = dir.path().join("golden");
    std::fs::create_dir(&golden).expect("dir");
    let out = ppmc(&[
        "run",
        "--junit",
        junit.to_str().expect("utf-8"),
        "--filter",
        "e0_undefined",
        "--repeat",
        "2",
        "--shard",
        "1/1",
        "--golden",
        golden.to_str().expect("utf-8"),
        "--artifacts",
        arts.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let xml = std::fs::read_to_string(&junit).expect("written");
    let report = quick_junit::Report::deserialize_from_str(&xml).expect("parses");
    assert_eq!(report.tests, 2);
    assert_eq!(report.errors, 2);
    let suite = &report.test_suites[0];
    assert_eq!(suite.name.as_str(), "ppmc-conformance shard 1/1");
    assert!(suite.timestamp.is_some(), "{xml}");
    let names: Vec<&str> = suite.test_cases.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "e0_undefined_command_code [pass 1]",
            "e0_undefined_command_code [pass 2]"
        ]
    );
    // junit-10.xsd: no `skipped` on testsuites; testsuite has time,
    // timestamp, hostname; the explanation is the element's text too.
    let root = xml
        .lines()
        .find(|l| l.starts_with("<testsuites"))
        .expect("root");
    assert!(!root.contains("skipped="), "{root}");
    let suite_line = xml
        .lines()
        .find(|l| l.trim_start().starts_with("<testsuite "))
        .expect("suite");
    for attr in [
        "time=",
        "timestamp=",
        "hostname=",
        "tests=",
        "failures=",
        "errors=",
    ] {
        assert!(suite_line.contains(attr), "{attr} in {suite_line}");
    }
    assert!(
        xml.contains("no golden trace for this scenario (record one with `ppmc record`)</error>"),
        "{xml}"
    );
    assert!(xml.contains("[[ATTACHMENT|"), "{xml}");
    assert!(xml.contains("property name=\"device_time.e0_undefined_command_code [pass 1]\""));
}

/// A soak's reports (`--repeat`): the first pass listed, then one test
/// case per scenario for the later passes with their counts and each
/// measurement's range; the record validates with its `pass` and
/// `repeated` fields, and the summary counts every run.
#[test]
fn a_soak_lists_the_first_pass_and_counts_the_rest() {
    let validator = schema();
    let dir = scratch("reports");
    let junit = dir.path().join("r.xml");
    let json = dir.path().join("run.json");
    let out = ppmc(&[
        "run",
        "--junit",
        junit.to_str().expect("utf-8"),
        "--json",
        json.to_str().expect("utf-8"),
        "--filter",
        "s3_3_5_constant_speed",
        "--repeat",
        "5",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stdout));
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("JSON");
    check(&validator, &record);
    let listed = record["scenarios"].as_array().expect("scenarios");
    let repeated = record["repeated"].as_array().expect("repeated");
    assert!(!listed.is_empty());
    assert_eq!(repeated.len(), listed.len(), "one entry per scenario");
    assert!(listed.iter().all(|s| s["pass"] == 1), "{listed:?}");
    assert_eq!(
        record["summary"]["passed"].as_u64().expect("count") as usize
            + record["summary"]["marginal"].as_u64().expect("count") as usize,
        5 * listed.len()
    );
    let r = &repeated[0];
    assert_eq!(
        (r["first_pass"].clone(), r["last_pass"].clone()),
        (2.into(), 5.into())
    );
    assert_eq!(r["runs"], 4);
    let m = &r["measurements"][0];
    assert_eq!(m["count"], 4, "{r}");
    assert!(m["min_ns"].as_u64() <= m["max_ns"].as_u64(), "{m}");

    let xml = std::fs::read_to_string(&junit).expect("written");
    let report = quick_junit::Report::deserialize_from_str(&xml).expect("parses");
    let suite = &report.test_suites[0];
    assert_eq!(report.tests, 2 * listed.len());
    assert_eq!(suite.test_cases.len(), 2 * listed.len());
    let name = listed[0]["name"].as_str().expect("name");
    let names: Vec<&str> = suite.test_cases.iter().map(|c| c.name.as_str()).collect();
    assert!(
        names.contains(&format!("{name} [pass 1]").as_str()),
        "{names:?}"
    );
    let soak = format!("{name} [passes 2-5]");
    assert!(names.contains(&soak.as_str()), "{names:?}");
    assert!(xml.contains(&format!("property name=\"device_time.{soak}\"")));
    assert!(xml.contains("repeated: 4 runs of passes 2-5"), "{xml}");
}
