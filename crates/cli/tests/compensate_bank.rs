//! `hystcomp compensate` with a model set (many channels, one column each) and `hystcomp bench
//! --channels`, through the built binary: each channel's drive is what `compensate` writes for
//! its own model alone, columns are found by channel name or position, bad input names the
//! channel and row, saturation of any channel gives exit status 4.

mod common;

use common::*;

use std::path::{Path, PathBuf};

use hystcomp_io::bank::ModelSet;
use hystcomp_io::data::{Column, ReadOptions, read_columns, write_csv};

/// A three-column trajectory (time, then one column per axis of the xyz set, named `names`),
/// each column its model driven by a voltage sweep (reachable).
fn trajectory(dir: &Path, names: [&str; 3]) -> PathBuf {
    let set = ModelSet::load(&models().join("table1-xyz-set.json")).unwrap();
    let n = 1500;
    let time: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
    let columns: Vec<Vec<f64>> = set
        .channels
        .iter()
        .enumerate()
        .map(|(c, ch)| {
            let mut plant = ch.model.model().unwrap();
            time.iter()
                .map(|t| {
                    let v = 5.0 - 4.0 * (2.0 * std::f64::consts::PI * t + c as f64).cos();
                    ch.model
                        .output_to_physical(plant.step(ch.model.normalise_input(v)))
                })
                .collect()
        })
        .collect();
    let path = dir.join("xyz.csv");
    write_csv(
        &path,
        &["time_s", names[0], names[1], names[2]],
        &[&time, &columns[0], &columns[1], &columns[2]],
    )
    .unwrap();
    path
}

/// `compensate --model MODEL --method ihc --desired DESIRED -o OUT`, then `extra`.
fn ihc_args<'a>(
    model: &'a Path,
    desired: &'a Path,
    out: &'a Path,
    extra: &[&'a str],
) -> Vec<&'a str> {
    let mut args = vec![
        "compensate",
        "--model",
        s(model),
        "--method",
        "ihc",
        "--desired",
        s(desired),
        "-o",
        s(out),
    ];
    args.extend(extra);
    args
}

fn columns(path: &Path, count: usize) -> Vec<Vec<f64>> {
    let wanted: Vec<Column> = (1..=count).map(Column::Index).collect();
    read_columns(path, &wanted, &ReadOptions::default())
        .unwrap()
        .values
}

#[test]
fn each_channel_is_its_own_model_compensated_alone() {
    let dir = tempfile::tempdir().unwrap();
    let desired = trajectory(dir.path(), ["x", "y", "z"]);
    let set_file = models().join("table1-xyz-set.json");
    let out = dir.path().join("drive.csv");
    let output = hystcomp(&ihc_args(&set_file, &desired, &out, &[]));
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stdout(&output).contains("3 channels"),
        "{}",
        stdout(&output)
    );
    let header = std::fs::read_to_string(&out).unwrap();
    assert!(
        header.starts_with(
            "time_s,drive_x_v,drive_y_v,drive_z_v,desired_x_um,desired_y_um,desired_z_um"
        ),
        "{}",
        header.lines().next().unwrap()
    );
    let bank = columns(&out, 7);
    // Each channel alone: its model in a file of its own, its column through `compensate`.
    let set = ModelSet::load(&set_file).unwrap();
    for (c, channel) in set.channels.iter().enumerate() {
        let model = dir.path().join(format!("{}.json", channel.name));
        channel.model.save(&model).unwrap();
        let single = dir.path().join(format!("single_{}.csv", channel.name));
        let output = hystcomp(&ihc_args(
            &model,
            &desired,
            &single,
            &["--desired-column", &(c + 2).to_string()],
        ));
        assert!(output.status.success(), "{}", stderr(&output));
        let alone = columns(&single, 2);
        assert_eq!(bank[c + 1], alone[1], "channel {c}");
    }
    // Columns by position when the names differ; --json reports every channel.
    let other = trajectory(dir.path(), ["a", "b", "c"]);
    let out2 = dir.path().join("drive2.csv");
    let output = hystcomp(&[
        "--json",
        "compensate",
        "--model",
        s(&set_file),
        "--method",
        "ihc",
        "--desired",
        s(&other),
        "-o",
        s(&out2),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let report: serde_json::Value = serde_json::from_str(&stdout(&output)).unwrap();
    assert_eq!(report["channels"].as_array().unwrap().len(), 3);
    assert_eq!(report["channels"][2]["name"], "z");
    assert_eq!(report["channels"][2]["desired_column"], "c");
    assert_eq!(columns(&out2, 4)[1..], bank[1..4]);
    // --desired-columns in another order: channel x reads column c (z's trajectory).
    let out3 = dir.path().join("drive3.csv");
    let output = hystcomp(&ihc_args(
        &set_file,
        &other,
        &out3,
        &["--desired-columns", "a,b,c"],
    ));
    assert!(output.status.success(), "{}", stderr(&output));
}

#[test]
fn each_channel_takes_its_own_drive_limits() {
    let dir = tempfile::tempdir().unwrap();
    let desired = trajectory(dir.path(), ["x", "y", "z"]);
    let set_file = models().join("table1-xyz-set.json");
    let run = |limits: &str, out: &Path| {
        hystcomp(&[
            "--json",
            "compensate",
            "--model",
            s(&set_file),
            "--method",
            "ihc",
            "--desired",
            s(&desired),
            "--limits",
            limits,
            "--allow-saturation",
            "-o",
            s(out),
        ])
    };
    // One pair per channel, each kept: the report's limits and the drives within them.
    let out = dir.path().join("drive.csv");
    let output = run("0:10,0:6,1:5", &out);
    assert!(output.status.success(), "{}", stderr(&output));
    let report: serde_json::Value = serde_json::from_str(&stdout(&output)).unwrap();
    let drives = columns(&out, 4);
    for (c, (lo, hi)) in [(0.0, 10.0), (0.0, 6.0), (1.0, 5.0)]
        .into_iter()
        .enumerate()
    {
        assert_eq!(report["channels"][c]["limits"][0].as_f64(), Some(lo), "{c}");
        assert_eq!(report["channels"][c]["limits"][1].as_f64(), Some(hi), "{c}");
        assert!(
            drives[c + 1].iter().all(|v| (lo..=hi).contains(v)),
            "channel {c} leaves {lo} .. {hi}"
        );
    }
    // One pair: every channel's.
    let shared = dir.path().join("shared.csv");
    let output = run("0:6", &shared);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(columns(&shared, 4)[2], drives[2]);
    // Two pairs for three channels, or two for one model: refused, nothing written.
    let refused = dir.path().join("refused.csv");
    assert_fails(
        &ihc_args(&set_file, &desired, &refused, &["--limits", "0:10,0:6"]),
        &["drive limits", "3 channels"],
    );
    let model = dir.path().join("x.json");
    ModelSet::load(&set_file).unwrap().channels[0]
        .model
        .save(&model)
        .unwrap();
    assert_fails(
        &ihc_args(
            &model,
            &desired,
            &refused,
            &["--desired-column", "2", "--limits", "0:10,0:6"],
        ),
        &["--limits gives 2 pairs for one model"],
    );
    assert!(!refused.exists());
}

#[test]
fn a_model_set_directory_holds_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let desired = trajectory(dir.path(), ["x", "y", "z"]);
    let set_dir = dir.path().join("set");
    std::fs::create_dir(&set_dir).unwrap();
    let set = ModelSet::load(&models().join("table1-xyz-set.json")).unwrap();
    for channel in &set.channels {
        channel
            .model
            .save(&set_dir.join(format!("{}.json", channel.name)))
            .unwrap();
    }
    let before: Vec<Vec<u8>> = ["x", "y", "z"]
        .iter()
        .map(|n| std::fs::read(set_dir.join(format!("{n}.json"))).unwrap())
        .collect();
    // Over one of its model files, or a new file beside them (the next run would read it as
    // a channel): refused, nothing written.
    for out in [set_dir.join("x.json"), set_dir.join("drive.csv")] {
        assert_fails(
            &ihc_args(&set_dir, &desired, &out, &[]),
            &["lies inside --model"],
        );
    }
    assert!(!set_dir.join("drive.csv").exists());
    for (n, bytes) in ["x", "y", "z"].iter().zip(&before) {
        assert_eq!(
            &std::fs::read(set_dir.join(format!("{n}.json"))).unwrap(),
            bytes,
            "{n}"
        );
    }
    // Beside the directory: written.
    let out = dir.path().join("drive.csv");
    let output = hystcomp(&ihc_args(&set_dir, &desired, &out, &[]));
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(columns(&out, 7).len(), 7);
}

#[test]
fn bad_input_names_the_channel() {
    let dir = tempfile::tempdir().unwrap();
    let desired = trajectory(dir.path(), ["x", "y", "z"]);
    let set_file = models().join("table1-xyz-set.json");
    let out = dir.path().join("drive.csv");
    // Two columns named for three channels.
    assert_fails(
        &ihc_args(&set_file, &desired, &out, &["--desired-columns", "x,y"]),
        &["--desired-columns", "3 channels"],
    );
    // A plant set for DIHC: channel 0 named.
    assert_fails(
        &[
            "compensate",
            "--model",
            s(&set_file),
            "--method",
            "dihc",
            "--desired",
            s(&desired),
            "-o",
            s(&out),
        ],
        &["channel 0 (x)"],
    );
    assert!(!out.exists());
    // Positions beyond reach on one channel: exit status 4, the channel named, the file written.
    let far = dir.path().join("far.csv");
    let time: Vec<f64> = (0..100).map(|k| k as f64 * 1e-3).collect();
    let ok: Vec<f64> = vec![30.0; 100];
    let beyond: Vec<f64> = vec![500.0; 100];
    write_csv(
        &far,
        &["time_s", "x", "y", "z"],
        &[&time, &ok, &beyond, &ok],
    )
    .unwrap();
    let output = hystcomp(&ihc_args(&set_file, &far, &out, &[]));
    assert_eq!(output.status.code(), Some(4), "{}", stderr(&output));
    assert!(stderr(&output).contains("channel y"), "{}", stderr(&output));
    assert!(
        !stderr(&output).contains("channel x"),
        "{}",
        stderr(&output)
    );
    assert!(out.exists());
    // --desired-columns naming the time column, or one column twice: refused.
    for (columns, expected) in [
        ("1,2,3", "is the time column"),
        ("2,2,3", "read the same column"),
        ("x,y,x", "read the same column"),
    ] {
        assert_fails(
            &[
                "compensate",
                "--model",
                s(&set_file),
                "--method",
                "ihc",
                "--desired",
                s(&desired),
                "--desired-columns",
                columns,
                "-o",
                s(&dir.path().join("columns.csv")),
            ],
            &[expected],
        );
    }
    assert!(!dir.path().join("columns.csv").exists());
    // --desired-columns without a set.
    assert_fails(
        &[
            "compensate",
            "--model",
            s(&models().join("table1-plant.json")),
            "--method",
            "ihc",
            "--desired",
            s(&far),
            "--desired-columns",
            "x,y",
            "-o",
            s(&dir.path().join("other.csv")),
        ],
        &["--desired-columns", "model set"],
    );
}

/// A file that has every channel's named column but cannot be read by name (a bad value in
/// one of them) is refused with that value's line: it is never read from other columns by
/// position instead, which would drive the channels from the wrong trajectories.
#[test]
fn a_bad_named_column_is_an_error_not_a_fallback() {
    let dir = tempfile::tempdir().unwrap();
    let set_file = models().join("table1-xyz-set.json");
    let out = dir.path().join("drive.csv");
    let path = dir.path().join("named.csv");
    let mut text = String::from("time_s,ref_x,x,y,z\n");
    for k in 0..50 {
        let z = if k == 17 {
            "abc".to_string()
        } else {
            "30".to_string()
        };
        text.push_str(&format!("{},31,30,30,{z}\n", k as f64 * 1e-3));
    }
    std::fs::write(&path, text).unwrap();
    assert_fails(
        &ihc_args(&set_file, &path, &out, &[]),
        &[
            "line 19",
            "\"abc\" is not a number",
            "named after the channels",
        ],
    );
    assert!(!out.exists());
    // Without the channels' names the columns are taken by position, and an index whose
    // channels run past the largest index is refused, not wrapped.
    let desired = trajectory(dir.path(), ["a", "b", "c"]);
    let huge = usize::MAX.to_string();
    assert_fails(
        &ihc_args(&set_file, &desired, &out, &["--desired-column", &huge]),
        &["leaves no column for channel 1"],
    );
    assert!(!out.exists());
}

#[test]
fn bench_times_the_banks() {
    let output = hystcomp(&[
        "--json",
        "bench",
        "--channels",
        "1,8",
        "--samples",
        "400",
        "--repeats",
        "1",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let report: serde_json::Value = serde_json::from_str(&stdout(&output)).unwrap();
    let figures = report["figures"].as_array().unwrap();
    // Seven methods, two channel counts, two precisions.
    assert_eq!(figures.len(), 28);
    for f in figures {
        let ns = f["median_ns_per_channel_step"].as_f64().unwrap();
        assert!(ns.is_finite() && ns > 0.0, "{f}");
    }
    assert!(
        figures
            .iter()
            .any(|f| f["what"] == "dihc" && f["channels"] == 8)
    );
    assert!(figures.iter().all(|f| f["vector_path"] != "best"));
    assert_eq!(report["clock"], "wall");
    assert_fails(&["bench", "--channels", "0"], &["--channels 0"]);
    assert_fails(&["bench", "--channels", "70000"], &["--channels 70000"]);
    assert_fails(
        &["bench", "--vector-path", "all"],
        &["--vector-path", "--channels"],
    );
    // A model file is not what the banks time: refused, not silently left out.
    let table1 = models().join("table1-plant.json");
    assert_fails(
        &["bench", "--channels", "1", "--model", s(&table1)],
        &["--model", "--channels"],
    );
}

#[test]
fn bench_times_each_vector_path_on_the_thread_cpu_clock() {
    let args = [
        "--json",
        "bench",
        "--channels",
        "8",
        "--samples",
        "400",
        "--repeats",
        "1",
        "--clock",
        "thread-cpu",
        "--vector-path",
        "all",
    ];
    let output = hystcomp(&args);
    if !cfg!(target_os = "linux") {
        assert!(!output.status.success());
        assert!(stderr(&output).contains("--clock thread-cpu"));
        hystcomp_testkit::skip("--clock thread-cpu is Linux only: checked that it is refused");
        return;
    }
    assert!(output.status.success(), "{}", stderr(&output));
    let report: serde_json::Value = serde_json::from_str(&stdout(&output)).unwrap();
    assert_eq!(report["clock"], "thread-cpu");
    let figures = report["figures"].as_array().unwrap();
    let paths: Vec<&str> = ["baseline", "avx2", "avx512"]
        .into_iter()
        .filter(|p| figures.iter().any(|f| f["vector_path"] == *p))
        .collect();
    // The baseline always; each figure once per path, seven methods, two precisions.
    assert!(paths.contains(&"baseline"), "{paths:?}");
    assert_eq!(figures.len(), 14 * paths.len());
    for f in figures {
        let ns = f["median_ns_per_channel_step"].as_f64().unwrap();
        assert!(ns.is_finite() && ns > 0.0, "{f}");
    }
}

/// The xyz set with channel `y` named `name` instead (JSON string text: escapes as written),
/// written to `file` in `dir`.
fn set_renaming_y(dir: &Path, name: &str, file: &str) -> PathBuf {
    let text = std::fs::read_to_string(models().join("table1-xyz-set.json")).unwrap();
    let renamed = text.replacen("\"name\": \"y\"", &format!("\"name\": \"{name}\""), 1);
    assert_ne!(renamed, text, "channel y is in the set");
    let set_file = dir.join(file);
    std::fs::write(&set_file, renamed).unwrap();
    set_file
}

/// A channel named after the time column is not driven by the clock: found by name, its
/// column is the time column, refused as an explicit `--desired-columns` naming it is (it
/// once read the time values silently and ignored the channel's own column).
#[test]
fn a_channel_named_after_the_time_column_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let desired = trajectory(dir.path(), ["x", "y", "z"]);
    let set_file = set_renaming_y(dir.path(), "time_s", "clock-set.json");
    let out = dir.path().join("drive.csv");
    assert_fails(
        &ihc_args(&set_file, &desired, &out, &["--allow-saturation"]),
        &["channel 1 (time_s)", "time column"],
    );
    assert!(!out.exists(), "nothing written");
}

/// A channel name with a line break (a column header cannot hold one) is refused when the
/// set is read, exit status 1, not when the drives are written (it once failed there, exit
/// status 3, after the whole run).
#[test]
fn a_channel_name_with_a_line_break_is_refused_when_read() {
    let dir = tempfile::tempdir().unwrap();
    let desired = trajectory(dir.path(), ["x", "y", "z"]);
    let set_file = set_renaming_y(dir.path(), "y\\nz", "broken-name-set.json");
    let out = dir.path().join("drive.csv");
    let output = hystcomp(&ihc_args(
        &set_file,
        &desired,
        &out,
        &["--allow-saturation"],
    ));
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(stderr(&output).contains("channel 1"), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("line break"),
        "{}",
        stderr(&output)
    );
    assert!(!out.exists(), "nothing written");
}
