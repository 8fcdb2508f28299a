//! The command line as users run it: exit codes and what it prints.

use crate::helpers::*;

#[test]
fn import_prints_a_summary_and_reports_nothing_changed_the_second_time() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    write_release(&root, &[3, 5]);
    let db = dir.path().join("cli.db");
    let run = || {
        enact_hub()
            .arg("import")
            .arg(&root)
            .arg("--db")
            .arg(&db)
            .output()
            .expect("run enact-hub import")
    };
    let first = run();
    let stderr = String::from_utf8_lossy(&first.stderr);
    assert!(first.status.success(), "{stderr}");
    assert!(
        stderr.contains("imported 4 items into dataset 'release'"),
        "{stderr}"
    );
    assert!(stderr.contains("frames: 16 (16 new, 0 reused)"), "{stderr}");
    let second = run();
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert!(second.status.success());
    assert!(stderr.contains("nothing changed"), "{stderr}");
}

#[test]
fn version_prints_the_crate_version_the_commit_and_the_schema_versions() {
    let out = enact_hub()
        .arg("--version")
        .output()
        .expect("run enact-hub --version");
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout.trim_end();
    assert_eq!(
        line,
        format!("enact-hub {}", enact_hub::app::version::version_line())
    );
    let expected_start = format!("enact-hub {} (commit ", env!("CARGO_PKG_VERSION"));
    assert!(line.starts_with(&expected_start), "{line}");
    // Built from a checkout, the commit is git's HEAD.
    if enact_hub::core::version::COMMIT != "unknown"
        && let Ok(head) = std::process::Command::new("git")
            .args(["-C", env!("CARGO_MANIFEST_DIR"), "rev-parse", "HEAD"])
            .output()
        && head.status.success()
    {
        let head = String::from_utf8_lossy(&head.stdout);
        assert!(
            line.contains(&format!("(commit {}, ", &head.trim()[..12])),
            "{line} is not HEAD {head}"
        );
    }
}

#[test]
fn invalid_rows_fail_the_import_with_line_numbers() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let good = write_record(&root, "t", true, 3, 1);
    write_qa_file(&root, &[good.to_string(), "{broken".to_owned()]);
    let out = enact_hub()
        .arg("import")
        .arg(&root)
        .arg("--db")
        .arg(dir.path().join("cli.db"))
        .output()
        .expect("run");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("line 2: invalid JSON"), "{stderr}");
    assert!(
        stderr.contains("1 invalid rows of 2; nothing was imported"),
        "{stderr}"
    );
}

#[test]
fn enact_sample_cli_counts() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let db = dir.path().join("cli.db");
    let no_images = fixtures.join("enact-sample/QA/enact_ordering_320_no_images.jsonl");
    let out = enact_hub()
        .arg("import")
        .arg(&no_images)
        .arg("--db")
        .arg(&db)
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("304 invalid rows of 320"), "{stderr}");
    assert_eq!(
        stderr.lines().filter(|l| l.starts_with("line ")).count(),
        304
    );
    let out = enact_hub()
        .arg("import")
        .arg(&no_images)
        .arg("--db")
        .arg(&db)
        .arg("--skip-invalid")
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("imported 16 items"), "{stderr}");
    assert!(stderr.contains("304 invalid rows skipped"), "{stderr}");
}

fn agreement_json(data: &str, args: &[&str]) -> (bool, serde_json::Value, String) {
    let dir = tempfile::tempdir().expect("tempdir");
    let input = dir.path().join("data.json");
    std::fs::write(&input, data).expect("write");
    let out = enact_hub()
        .arg("agreement")
        .arg("--input")
        .arg(&input)
        .args(args)
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let json = serde_json::from_slice(&out.stdout).unwrap_or(serde_json::Value::Null);
    (out.status.success(), json, stderr)
}

#[test]
fn agreement_prints_alpha_with_a_seeded_interval() {
    // Krippendorff (2011), 4 observers x 12 units, nominal: alpha = 113/152.
    let data = r#"{"data": [[1,2,3,3,2,1,4,1,2,null,null,null],[1,2,3,3,2,2,4,1,2,5,null,3],
                             [null,3,3,3,2,3,4,2,2,5,1,null],[1,2,3,3,2,4,4,1,2,5,1,null]]}"#;
    let (ok, json, stderr) = agreement_json(
        data,
        &["--level", "nominal", "--bootstrap", "200", "--seed", "9"],
    );
    assert!(ok, "{stderr}");
    let alpha = json["alpha"].as_f64().expect("alpha");
    assert!((alpha - 113.0 / 152.0).abs() < 1e-12, "{alpha}");
    assert_eq!(json["units_used"], 11);
    assert_eq!(json["bootstrap"]["seed"], 9);
    let (lo, hi) = (
        json["bootstrap"]["ci_low"].as_f64().expect("low"),
        json["bootstrap"]["ci_high"].as_f64().expect("high"),
    );
    assert!(lo < alpha && alpha <= hi, "{lo} {alpha} {hi}");
    let (_, again, _) = agreement_json(
        data,
        &["--level", "nominal", "--bootstrap", "200", "--seed", "9"],
    );
    assert_eq!(
        json["bootstrap"], again["bootstrap"],
        "same seed, same interval"
    );
}

#[test]
fn agreement_without_variation_is_null_with_a_reason() {
    let (ok, json, _) = agreement_json(r#"{"data": [[1, 1], [1, 1]]}"#, &["--level", "ordinal"]);
    assert!(ok);
    assert!(json["alpha"].is_null());
    assert!(
        json["reason"]
            .as_str()
            .expect("reason")
            .contains("expected disagreement is zero")
    );
}

#[test]
fn agreement_input_errors_name_coder_and_unit() {
    let (ok, _, stderr) =
        agreement_json(r#"{"data": [[1, "x"], [1, 1]]}"#, &["--level", "ordinal"]);
    assert!(!ok);
    assert!(stderr.contains("data[0][1]"), "{stderr}");
}

#[test]
fn generate_writes_a_release_that_imports_with_semantic_scoring() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let replayed = fixtures.join("enact-parity/replayed_activities");
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("generated");
    let run = enact_hub()
        .args(["generate"])
        .arg(&replayed)
        .arg("--out")
        .arg(&out)
        .args(["--steps", "3,4", "--num-to-sample", "1"])
        .output()
        .expect("run generate");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    // Three tasks, two step lengths, both directions, one path each.
    assert!(
        stderr.contains("generated 12 items (6 forward, 6 inverse)"),
        "{stderr}"
    );
    assert!(out.join("generation_summary.json").is_file());
    let import = enact_hub()
        .arg("import")
        .arg(&out)
        .arg("--db")
        .arg(dir.path().join("g.db"))
        .arg("--scene-graphs")
        .arg(out.join("replayed_activities"))
        .output()
        .expect("run import");
    let stderr = String::from_utf8_lossy(&import.stderr);
    assert!(import.status.success(), "{stderr}");
    assert!(stderr.contains("imported 12 items"), "{stderr}");
    assert!(stderr.contains("12 from scene graphs"), "{stderr}");
}

#[test]
fn generate_names_a_missing_replay_folder_and_bad_steps() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = enact_hub()
        .arg("generate")
        .arg(dir.path().join("nope"))
        .arg("--out")
        .arg(dir.path().join("out"))
        .output()
        .expect("run");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("nope"));
    let out = enact_hub()
        .arg("generate")
        .arg(dir.path())
        .arg("--out")
        .arg(dir.path().join("out"))
        .args(["--steps", "2..5"])
        .output()
        .expect("run");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("step length 2 is outside 3..10"));
}

#[test]
fn annotator_create_prints_a_single_use_invite_link_last() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = dir.path().join("cli.db");
    let run = |name: &str| {
        enact_hub()
            .args([
                "annotator",
                "create",
                "--name",
                name,
                "--admin",
                "--base-url",
            ])
            .arg("https://annotate.example/")
            .arg("--db")
            .arg(&db)
            .output()
            .expect("run enact-hub annotator create")
    };
    let first = run("alice");
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let stdout = String::from_utf8_lossy(&first.stdout);
    let last = stdout.lines().last().expect("a line");
    let token = last
        .strip_prefix("https://annotate.example/invite/")
        .unwrap_or_else(|| panic!("last line is not an invite link: {stdout}"));
    assert_eq!(token.len(), 64);
    let again = run("alice");
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("already exists"));
    let bad = run("a b");
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("is not allowed"));
}
