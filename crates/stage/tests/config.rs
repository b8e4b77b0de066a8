//! The stage file: defaults, round trips and every kind of bad file.

use hystcomp_stage::{HysteresisModel, Stage, StageConfig, StageError};

const DEFAULT_TOML: &str = include_str!("../stages/default.toml");

#[test]
fn shipped_default_file_parses_to_exactly_the_built_in_default() {
    let parsed = StageConfig::from_toml_str(DEFAULT_TOML).unwrap();
    assert_eq!(parsed, StageConfig::default());
    assert_eq!(
        StageConfig::from_toml_str("").unwrap(),
        StageConfig::default()
    );
}

#[test]
fn shipped_default_file_lists_every_field() {
    // Every key of the serialised configuration appears in the shipped file.
    let written: toml::Table = toml::from_str(&StageConfig::default().to_toml_string()).unwrap();
    let shipped: toml::Table = toml::from_str(DEFAULT_TOML).unwrap();
    fn keys(prefix: &str, t: &toml::Table, out: &mut Vec<String>) {
        for (k, v) in t {
            let path = format!("{prefix}{k}");
            match v {
                toml::Value::Table(sub) => keys(&format!("{path}."), sub, out),
                _ => out.push(path),
            }
        }
    }
    let (mut a, mut b) = (Vec::new(), Vec::new());
    keys("", &written, &mut a);
    keys("", &shipped, &mut b);
    a.sort();
    b.sort();
    assert_eq!(a, b);
}

#[test]
fn effective_configuration_round_trips_through_toml() {
    let mut config = StageConfig::default();
    config.hysteresis.model = HysteresisModel::BoucWen;
    config.mechanics.damping_ratio = 0.12;
    config.creep.decades = 3;
    let text = config.to_toml_string();
    assert!(text.contains("model = \"bouc-wen\""), "{text}");
    assert_eq!(StageConfig::from_toml_str(&text).unwrap(), config);
}

#[test]
fn partial_file_changes_only_what_it_names() {
    let config = StageConfig::from_toml_str(
        "[mechanics]\nresonance_hz = 650.0\n[hysteresis]\nmodel = \"bouc-wen\"\n",
    )
    .unwrap();
    let mut expected = StageConfig::default();
    expected.mechanics.resonance_hz = 650.0;
    expected.hysteresis.model = HysteresisModel::BoucWen;
    assert_eq!(config, expected);
}

/// Each bad file, the field its error must name and a fragment of the requirement.
const BAD_FILES: &[(&str, &str, &str)] = &[
    ("sample_rate_hz = 0.0", "sample_rate_hz", "> 0"),
    ("sample_rate_hz = -10000.0", "sample_rate_hz", "> 0"),
    ("sample_rate_hz = nan", "sample_rate_hz", "finite"),
    ("sample_rate_hz = 1e300", "sample_rate_hz", "at most 1e6 Hz"),
    ("sample_rate_hz = 1e7", "sample_rate_hz", "at most 1e6 Hz"),
    (
        "[mechanics]\ndamping_ratio = -0.05",
        "mechanics.damping_ratio",
        "(0, 10]",
    ),
    (
        "[mechanics]\ndamping_ratio = 0.0",
        "mechanics.damping_ratio",
        "(0, 10]",
    ),
    (
        "[mechanics]\nresonance_hz = 6000.0",
        "mechanics.resonance_hz",
        "Nyquist",
    ),
    (
        "[mechanics]\nresonance_hz = -800.0",
        "mechanics.resonance_hz",
        "> 0",
    ),
    (
        "[amplifier]\nbandwidth_hz = -3.0",
        "amplifier.bandwidth_hz",
        "> 0",
    ),
    ("[amplifier]\ngain = 0.0", "amplifier.gain", "> 0"),
    (
        "[amplifier]\noutput_min_v = 150.0\noutput_max_v = 0.0",
        "amplifier.output_min_v..amplifier.output_max_v",
        "increasing",
    ),
    (
        "[amplifier]\npeak_current_ma = 0.0",
        "amplifier.peak_current_ma",
        "> 0",
    ),
    (
        "[amplifier]\nload_capacitance_uf = inf",
        "amplifier.load_capacitance_uf",
        "finite",
    ),
    (
        "[dac]\nmin_v = 10.0\nmax_v = -10.0",
        "dac.min_v..dac.max_v",
        "increasing",
    ),
    ("[dac]\nbits = 0", "dac.bits", "1..=32"),
    ("[adc]\nbits = 40", "adc.bits", "1..=32"),
    (
        "[adc]\nmin_v = 5.0\nmax_v = 5.0",
        "adc.min_v..adc.max_v",
        "increasing",
    ),
    (
        "[hysteresis.preisach]\nvoltage_range_v = [150.0, 0.0]",
        "hysteresis.preisach.voltage_range_v",
        "increasing",
    ),
    (
        "[hysteresis.preisach]\nstroke_um = -75.0",
        "hysteresis.preisach.stroke_um",
        "> 0",
    ),
    (
        "[hysteresis.preisach]\nreversible_fraction = 1.5",
        "hysteresis.preisach.reversible_fraction",
        "[0, 0.999]",
    ),
    (
        "[hysteresis.preisach]\nrelay_width_sd = 0.0",
        "hysteresis.preisach.relay_width_sd",
        "[0.001, 10]",
    ),
    (
        "[hysteresis.preisach]\ndensity_tilt = -1.0",
        "hysteresis.preisach.density_tilt",
        "[-0.99, 0.99]",
    ),
    (
        "[hysteresis.preisach]\ngrid_cells = 4",
        "hysteresis.preisach.grid_cells",
        "16..=2048",
    ),
    (
        "[hysteresis.bouc_wen]\nb = -0.1",
        "hysteresis.bouc_wen.b",
        "> 0",
    ),
    (
        "[hysteresis.bouc_wen]\ngamma = 0.02",
        "hysteresis.bouc_wen.gamma",
        "[-b, b]",
    ),
    (
        "[hysteresis.bouc_wen]\nd_p_um_per_v = 0.0",
        "hysteresis.bouc_wen.d_p_um_per_v",
        "> 0",
    ),
    (
        "[creep]\npercent_per_decade = -1.0",
        "creep.percent_per_decade",
        "[0, 10]",
    ),
    (
        "[creep]\nfirst_time_constant_s = 0.0",
        "creep.first_time_constant_s",
        "> 0",
    ),
    ("[creep]\ndecades = 0", "creep.decades", "1..=12"),
    (
        "[creep]\nelements_per_decade = 0",
        "creep.elements_per_decade",
        "1..=10",
    ),
    (
        "[sensor]\nnoise_rms_nm = -5.0",
        "sensor.noise_rms_nm",
        "[0, 1e6]",
    ),
    (
        "[sensor]\nsensitivity_v_per_um = 0.0",
        "sensor.sensitivity_v_per_um",
        "> 0",
    ),
    (
        "[sensor]\nnonlinearity_percent = 20.0",
        "sensor.nonlinearity_percent",
        "[0, 5]",
    ),
];

#[test]
fn impossible_values_are_refused_with_the_field_named() {
    for (text, field, requirement) in BAD_FILES {
        let error = StageConfig::from_toml_str(text).unwrap_err();
        assert_eq!(error.field(), Some(*field), "{text}: {error}");
        let message = error.to_string();
        assert!(
            message.starts_with(&format!("{field} must be")) && message.contains(requirement),
            "{text}: {message}"
        );
        // The same configuration built in code is refused by Stage::new too.
        if let Ok(config) = toml::from_str::<StageConfig>(text) {
            assert!(matches!(
                Stage::new(&config, 0),
                Err(StageError::Invalid { .. })
            ));
        }
    }
}

#[test]
fn negative_bandwidth_message_reads_as_documented() {
    let error = StageConfig::from_toml_str("[amplifier]\nbandwidth_hz = -3").unwrap_err();
    assert_eq!(
        error.to_string(),
        "amplifier.bandwidth_hz must be > 0, got -3"
    );
}

#[test]
fn unknown_keys_and_wrong_types_are_refused_with_the_key_named() {
    for (text, key) in [
        ("sample_rate = 10000.0", "sample_rate"),
        ("[mechanics]\nresonance = 800.0", "resonance"),
        ("[hysteresis.preisach]\nwidth = 0.2", "width"),
        ("[amplfier]\ngain = 15.0", "amplfier"),
        ("[mechanics]\nresonance_hz = \"fast\"", "resonance_hz"),
        ("[hysteresis]\nmodel = \"mpim-typo\"", "mpim-typo"),
    ] {
        let error = StageConfig::from_toml_str(text).unwrap_err();
        assert!(
            matches!(error, StageError::Parse { .. }),
            "{text}: {error:?}"
        );
        assert!(error.to_string().contains(key), "{text}: {error}");
    }
}

#[test]
fn missing_file_is_an_io_error_naming_the_path() {
    let path = std::path::Path::new("/nonexistent/dir/stage.toml");
    let error = StageConfig::from_toml_file(path).unwrap_err();
    assert!(matches!(error, StageError::Io { .. }));
    assert!(error.to_string().contains("/nonexistent/dir/stage.toml"));
}

/// The full-scale command drives the amplifier to its upper rail when the DAC can write it,
/// and is the DAC's top otherwise (a low-gain amplifier); such a stage is valid, and at full
/// command it reaches a stroke below the rail's in proportion.
#[test]
fn full_scale_command_is_the_rail_or_the_dac_top_whichever_comes_first() {
    let default = StageConfig::default();
    assert_eq!(
        default.full_scale_command_v(),
        default.amplifier.output_max_v / default.amplifier.gain
    );
    for gain in [2.0, 5.0, 10.0, 15.0, 30.0] {
        let mut config = default.clone();
        config.amplifier.gain = gain;
        config.validate().unwrap();
        let top = config.full_scale_command_v();
        assert!(top <= config.dac.max_v && top * gain <= config.amplifier.output_max_v + 1e-9);
        // One of the two bounds is met with equality.
        let at_rail = (top * gain - config.amplifier.output_max_v).abs() < 1e-9;
        assert!(at_rail || top == config.dac.max_v, "gain {gain}: {top} V");
    }
    let mut weak = default.clone();
    weak.amplifier.gain = 5.0;
    let stroke = hystcomp_stage::quasi_static_stroke_um(&weak).unwrap();
    let full = hystcomp_stage::quasi_static_stroke_um(&default).unwrap();
    assert!(stroke < 0.6 * full, "{stroke} um of {full} um");
}
