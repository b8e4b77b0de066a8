//! Model sets and the bank in physical units: every channel of a `ScaledBank` gives what a
//! `ScaledCompensator` built from its own model file gives, bit for bit, in every method, on
//! random sets (each channel its own scales, weights and limits) and trajectories with jumps,
//! NaN and out-of-reach positions; sets read from a model-set file, a directory and a single
//! model file; refusals name the channel.

use std::path::PathBuf;

use hystcomp_core::CoreError;
use hystcomp_io::bank::{Channel, ModelSet, ModelSetError, ScaledBank};
use hystcomp_io::compensator::{Method, ScaledCompensator, UnstableDelay};
use hystcomp_io::model_file::{CreepPart, Direction, ModelFile};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn models_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models")
}

fn example(name: &str) -> ModelFile {
    ModelFile::load(&models_dir().join(name)).unwrap()
}

/// `base` with its weights scaled by `weight`, its output span by `span` and its output offset
/// moved by `offset` (a channel of its own).
fn variant(base: &ModelFile, weight: f64, span: f64, offset: f64) -> ModelFile {
    let mut m = base.clone();
    m.weights = m.weights.iter().map(|b| b * weight).collect();
    if base.direction == Direction::Plant {
        m.output.scale *= span;
        m.output.offset += offset;
    } else {
        m.input.scale *= span;
        m.input.offset += offset;
    }
    m.validate().unwrap();
    m
}

fn set_of(files: Vec<ModelFile>) -> ModelSet {
    let channels = files
        .into_iter()
        .enumerate()
        .map(|(k, model)| Channel {
            name: format!("axis_{k}"),
            model,
        })
        .collect();
    ModelSet::new(Some("test".into()), channels).unwrap()
}

/// A simple deterministic generator (the proptest seed drives it).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

proptest! {
    #![proptest_config(Config {
        cases: 24,
        rng_seed: RngSeed::Fixed(1604),
        failure_persistence: None,
        ..Config::default()
    })]

    /// Each channel of the bank equals its own `ScaledCompensator`, bit for bit, with the
    /// same diagnostics, for every method.
    #[test]
    fn every_channel_equals_its_scaled_compensator(seed in any::<u64>(), channels in 1usize..12, method in 0usize..7, per_channel_limits in any::<bool>()) {
        let method = Method::ALL[method];
        let mut rng = Lcg(seed);
        let base = if method == Method::Dihc { example("table2-inverse.json") } else { example("table1-plant.json") };
        let files: Vec<ModelFile> = (0..channels)
            .map(|_| variant(&base, 0.8 + 0.4 * rng.next(), 0.5 + rng.next(), 10.0 * rng.next() - 5.0))
            .collect();
        let limits: Vec<(f64, f64)> = (0..channels)
            .map(|_| (0.5 * rng.next(), 8.0 + 2.0 * rng.next()))
            .collect();
        let limits = if per_channel_limits { Some(limits) } else { None };
        let set = set_of(files.clone());
        let unstable = UnstableDelay::Allow;
        let mut bank = ScaledBank::new(&set, method, limits.as_deref(), unstable).unwrap();
        let mut singles: Vec<ScaledCompensator> = files
            .iter()
            .enumerate()
            .map(|(k, f)| ScaledCompensator::with_unstable_delay(f, method, limits.as_ref().map(|l| l[k]), unstable).unwrap())
            .collect();
        let mut control = vec![0.0; channels];
        for k in 0..300 {
            let desired: Vec<f64> = (0..channels)
                .map(|_| {
                    let u = rng.next();
                    if u < 0.02 {
                        f64::NAN
                    } else if u < 0.05 {
                        1e3 * (rng.next() - 0.5)
                    } else {
                        let t = k as f64 * 0.03 + u;
                        40.0 + 30.0 * t.sin()
                    }
                })
                .collect();
            bank.step(&desired, &mut control).unwrap();
            for (c, s) in singles.iter_mut().enumerate() {
                let expected = s.step(desired[c]);
                prop_assert_eq!(control[c].to_bits(), expected.to_bits(), "{} sample {} channel {}", method, k, c);
            }
        }
        for (c, s) in singles.iter().enumerate() {
            prop_assert_eq!(bank.diagnostics(c).unwrap(), s.diagnostics());
            prop_assert_eq!(bank.limits(c).unwrap(), s.limits());
        }
    }
}

#[test]
fn a_model_set_file_round_trips_and_loads_three_ways() {
    let set = ModelSet::load(&models_dir().join("table1-xyz-set.json")).unwrap();
    assert_eq!(set.names(), ["x", "y", "z"]);
    assert_eq!(ModelSet::from_json(&set.to_json()).unwrap(), set);
    let dir = tempfile::tempdir().unwrap();
    // Saved and read back.
    let file = dir.path().join("set.json");
    set.save(&file).unwrap();
    assert_eq!(ModelSet::load(&file).unwrap(), set);
    // A directory of model files, in the order of their names.
    let models = dir.path().join("axes");
    std::fs::create_dir(&models).unwrap();
    for c in set.channels.iter().rev() {
        c.model
            .save(&models.join(format!("{}.json", c.name)))
            .unwrap();
    }
    std::fs::write(models.join("notes.txt"), "not a model").unwrap();
    let from_dir = ModelSet::load(&models).unwrap();
    assert_eq!(from_dir.names(), ["x", "y", "z"]);
    for (a, b) in from_dir.channels.iter().zip(&set.channels) {
        assert_eq!(a.model.thresholds, b.model.thresholds);
        assert_eq!(a.model.weights, b.model.weights);
        assert_eq!(a.model.output, b.model.output);
    }
    // A single model file: one channel named by its stem.
    let one = ModelSet::load(&models_dir().join("table1-plant.json")).unwrap();
    assert_eq!(one.names(), ["table1-plant"]);
    assert_eq!(one.channels[0].model, example("table1-plant.json"));
}

fn set_error(text: &str) -> String {
    ModelSet::from_json(text).unwrap_err().to_string()
}

#[test]
fn bad_sets_are_refused_naming_the_channel() {
    let good = std::fs::read_to_string(models_dir().join("table1-xyz-set.json")).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&good).unwrap();
    // A channel whose thresholds are unsorted: named by index and name.
    value["channels"][1]["model"]["thresholds"][3] = serde_json::json!(0.05);
    let message = set_error(&value.to_string());
    assert!(
        message.starts_with("model set: channel 1 (y): "),
        "{message}"
    );
    // Read from a file, from a directory of model files or as one model file: the error names
    // the file holding the channel's model, then the channel.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bad-set.json");
    std::fs::write(&file, value.to_string()).unwrap();
    let err = ModelSet::load(&file).unwrap_err();
    assert!(
        matches!(&err, ModelSetError::File { channel: 1, name, path, .. }
            if name == "y" && *path == file.display().to_string()),
        "{err:?}"
    );
    assert!(
        err.to_string()
            .starts_with(&format!("{}: channel 1 (y): ", file.display())),
        "{err}"
    );
    let channels = dir.path().join("channels");
    std::fs::create_dir(&channels).unwrap();
    for (k, name) in ["a", "b"].iter().enumerate() {
        std::fs::write(
            channels.join(format!("{name}.json")),
            value["channels"][k]["model"].to_string(),
        )
        .unwrap();
    }
    let single = channels.join("b.json");
    let err = ModelSet::load(&channels).unwrap_err();
    assert!(
        err.to_string()
            .starts_with(&format!("{}: channel 1 (b): ", single.display())),
        "{err}"
    );
    let err = ModelSet::load(&single).unwrap_err();
    assert!(
        err.to_string()
            .starts_with(&format!("{}: channel 0 (b): ", single.display())),
        "{err}"
    );
    // An error that names the file itself (a format_version this build does not read): the
    // path once, in every form of the set.
    let mut future = value.clone();
    future["channels"][1]["model"]["format_version"] = serde_json::json!(9);
    std::fs::write(&file, future.to_string()).unwrap();
    std::fs::write(&single, future["channels"][1]["model"].to_string()).unwrap();
    for (set, path) in [(&file, &file), (&channels, &single), (&single, &single)] {
        let message = ModelSet::load(set).unwrap_err().to_string();
        let shown = path.display().to_string();
        assert_eq!(message.matches(&shown).count(), 1, "{message}");
        assert!(message.contains("format_version 9"), "{message}");
    }
    // Another format, version, field; no channel; a name twice.
    assert!(
        set_error(r#"{"format": "x", "format_version": 1, "channels": []}"#).contains("format")
    );
    assert!(
        set_error(r#"{"format": "hystcomp-model-set", "format_version": 9, "channels": []}"#)
            .contains("format_version 9")
    );
    assert!(
        set_error(r#"{"format": "hystcomp-model-set", "format_version": 1, "channels": []}"#)
            .contains("no channel")
    );
    assert!(
        set_error(r#"{"format": "hystcomp-model-set", "format_version": 1, "chanels": []}"#)
            .contains("unknown field")
    );
    // Not JSON, JSON that is not an object, a channel that is not an object, a channel's
    // model beyond a model file's 16 MiB (refused before it is parsed).
    assert!(set_error("{\"format\": ").contains("is not valid JSON"));
    assert!(set_error("[1, 2]").contains("is not a JSON object"));
    assert!(
        set_error(r#"{"format": "hystcomp-model-set", "format_version": 1, "channels": [3]}"#)
            .contains("channel 0: not an object")
    );
    let huge = format!(
        r#"{{"format": "hystcomp-model-set", "format_version": 1, "channels": [{{"name": "a", "model": {{"pad": "{}"}}}}]}}"#,
        "p".repeat(17 << 20)
    );
    let message = set_error(&huge);
    assert!(
        message.contains("channel 0 (a): its model is larger than the 16 MiB"),
        "{}",
        &message[..message.len().min(300)]
    );
    // More entries than a set may hold: refused while the array is read, the count named
    // (and an array that is not one, as no array).
    let many = format!(
        r#"{{"format": "hystcomp-model-set", "format_version": 1, "channels": [{}0]}}"#,
        "0,".repeat(hystcomp_io::bank::MAX_CHANNELS)
    );
    let message = set_error(&many);
    assert!(
        message.contains("more than the 65536 channels"),
        "{message}"
    );
    let exactly = format!(
        r#"{{"format": "hystcomp-model-set", "format_version": 1, "channels": [{}0]}}"#,
        "0,".repeat(hystcomp_io::bank::MAX_CHANNELS - 1)
    );
    assert!(set_error(&exactly).contains("channel 0: not an object"));
    assert!(
        set_error(r#"{"format": "hystcomp-model-set", "format_version": 1, "channels": {}}"#)
            .contains("no \"channels\" array")
    );
    let mut twice: serde_json::Value = serde_json::from_str(&good).unwrap();
    twice["channels"][2]["name"] = serde_json::json!("x");
    assert!(set_error(&twice.to_string()).contains("used twice"));
    let mut nameless: serde_json::Value = serde_json::from_str(&good).unwrap();
    nameless["channels"][0]
        .as_object_mut()
        .unwrap()
        .remove("name");
    assert_eq!(
        ModelSet::from_json(&nameless.to_string()).unwrap().names(),
        ["channel_0", "y", "z"]
    );
    // Missing files and empty directories name the path.
    let dir = tempfile::tempdir().unwrap();
    let message = ModelSet::load(dir.path()).unwrap_err().to_string();
    assert!(message.contains("no model file"), "{message}");
    let message = ModelSet::load(&dir.path().join("missing.json"))
        .unwrap_err()
        .to_string();
    assert!(message.contains("missing.json"), "{message}");
}

/// A directory set's model files together are bounded as one set file is: a directory of
/// links to one large model file is refused before any of them is parsed,
/// naming the file and channel where the sum passed it. Whether a file is a set is decided by
/// its `format` field alone.
#[cfg(unix)]
#[test]
fn a_directory_set_is_bounded_in_total_and_sets_are_told_by_their_format() {
    use hystcomp_io::bank::{MAX_MODEL_SET_BYTES, is_model_set};
    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(models_dir().join("table1-plant.json")).unwrap();
    let mut padded: serde_json::Value = serde_json::from_str(&good).unwrap();
    padded["description"] = serde_json::json!("p".repeat(1 << 20));
    let big = dir.path().join("big.json");
    std::fs::write(&big, padded.to_string()).unwrap();
    let size = std::fs::metadata(&big).unwrap().len();
    let links = dir.path().join("links");
    std::fs::create_dir(&links).unwrap();
    let count = MAX_MODEL_SET_BYTES / size + 2;
    for k in 0..count {
        std::os::unix::fs::symlink(&big, links.join(format!("c{k:03}.json"))).unwrap();
    }
    let message = ModelSet::load(&links).unwrap_err().to_string();
    let passed = MAX_MODEL_SET_BYTES / size;
    assert!(
        message.contains("add up to more than the 256 MiB")
            && message.contains(&format!("c{passed:03}.json, channel {passed})")),
        "{message}"
    );
    // Two of them are a set.
    let two = dir.path().join("two");
    std::fs::create_dir(&two).unwrap();
    for k in 0..2 {
        std::os::unix::fs::symlink(&big, two.join(format!("c{k}.json"))).unwrap();
    }
    assert_eq!(ModelSet::load(&two).unwrap().len(), 2);
    // A set by its format field only: a set file is, a model file or a file whose format is
    // not the set's (or not a string) is not.
    let set_file = models_dir().join("table1-xyz-set.json");
    assert!(is_model_set(&set_file));
    assert!(is_model_set(&two));
    assert!(!is_model_set(&big));
    for (k, text) in [r#"{"format": 3}"#, r#"{"format": "other"}"#, "[1]", "{"]
        .iter()
        .enumerate()
    {
        let file = dir.path().join(format!("f{k}.json"));
        std::fs::write(&file, text).unwrap();
        assert!(!is_model_set(&file), "{text}");
    }
}

/// One model of many operators pads every channel of its bank to its rows: a bank whose
/// storage would pass `MAX_BANK_VALUES` is refused before anything is allocated (4 096
/// channels, one of 10 000 operators: 512 blocks x 50 011 rows x 8 lanes, 205 million values),
/// and the same channels without it are built.
#[test]
fn a_bank_too_large_for_its_storage_bound_is_refused_before_allocating() {
    let base = example("table1-plant.json");
    let mut big = base.clone();
    let n = 10_000;
    big.thresholds = (0..n).map(|i| i as f64 / n as f64).collect();
    big.weights = vec![base.weights.iter().sum::<f64>() / n as f64; n];
    big.validate().unwrap();
    let mut files = vec![base.clone(); 4096];
    files[17] = big;
    let err = ScaledBank::new(&set_of(files), Method::Ihc, None, UnstableDelay::Refuse)
        .expect_err("refused");
    let message = err.to_string();
    assert!(message.contains("values of bank storage"), "{message}");
    assert!(
        message.contains(&hystcomp_core::MAX_BANK_VALUES.to_string()),
        "{message}"
    );
    assert!(
        ScaledBank::new(
            &set_of(vec![base; 4096]),
            Method::Ihc,
            None,
            UnstableDelay::Refuse
        )
        .is_ok()
    );
}

#[test]
fn a_refused_channel_is_named_when_the_bank_is_built() {
    let set = ModelSet::load(&models_dir().join("table1-xyz-set.json")).unwrap();
    // DIHC needs inverse models: channel 0 named.
    let err = ScaledBank::new(&set, Method::Dihc, None, UnstableDelay::Refuse).unwrap_err();
    assert!(
        matches!(&err, ModelSetError::Channel { channel: 0, name, .. } if name == "x"),
        "{err}"
    );
    // Table 1's delayed WIHC loop gain is 1.66: refused, channel 0 named; allowed explicitly.
    let err = ScaledBank::new(&set, Method::WihcDelayed, None, UnstableDelay::Refuse).unwrap_err();
    assert!(err.to_string().starts_with("channel 0 (x): "), "{err}");
    assert!(ScaledBank::new(&set, Method::WihcDelayed, None, UnstableDelay::Allow).is_ok());
    // Limits that are not increasing for channel 2.
    let err = ScaledBank::new(
        &set,
        Method::Ihc,
        Some(&[(0.0, 10.0), (0.0, 10.0), (5.0, 1.0)]),
        UnstableDelay::Refuse,
    )
    .unwrap_err();
    assert!(err.to_string().starts_with("channel 2 (z): "), "{err}");
    // Limits for another number of channels.
    let err = ScaledBank::new(
        &set,
        Method::Ihc,
        Some(&[(0.0, 10.0), (0.0, 10.0)]),
        UnstableDelay::Refuse,
    )
    .unwrap_err();
    assert!(err.to_string().contains("drive limits"), "{err}");
    // Limits are given once per channel, not per sample: no word of signals.
    assert!(!err.to_string().contains("whole signal"), "{err}");
    // Ticks of the wrong size: a whole signal may be a multiple of the channel count.
    let mut bank = ScaledBank::new(&set, Method::Ihc, None, UnstableDelay::Refuse).unwrap();
    let err = bank.step(&[1.0, 2.0], &mut [0.0; 3]).unwrap_err();
    assert!(
        matches!(err, CoreError::ChannelCount { found: 2, .. }),
        "{err}"
    );
    assert!(
        err.to_string().contains("a whole signal: a multiple of 3"),
        "{err}"
    );
    assert!(bank.process(&[1.0; 7], &mut [0.0; 7]).is_err());
    assert_eq!(bank.names(), ["x", "y", "z"]);
    assert_eq!(bank.desired_unit(1), Some("um"));
    assert_eq!(bank.control_unit(1), Some("V"));
}

#[test]
fn a_model_with_links_is_refused_in_a_bank() {
    let mut linked = example("table1-plant.json");
    linked.format_version = 2;
    linked.sample_rate_hz = Some(1000.0);
    linked.creep = Some(CreepPart {
        origin: 0.0,
        time_constants_s: vec![0.1, 1.0],
        weights: vec![0.02, 0.03],
    });
    linked.validate().unwrap();
    let set = set_of(vec![example("table1-plant.json"), linked]);
    let err = ScaledBank::new(&set, Method::Ihc, None, UnstableDelay::Refuse).unwrap_err();
    let message = err.to_string();
    assert!(message.contains("channel 1 (axis_1)"), "{message}");
    assert!(message.contains("creep or vibration"), "{message}");
}
