//! One learned model per catalog bearing (issue 30 item 3): the shipped models/ holds a model
//! for every bearing of the catalog, each made by the training specs for its bearing and naming
//! fresh records of it; `twin.learned_model` and `analyze --learned` take the directory and
//! judge each signal by the model of its bearing; a directory that cannot judge every sensor is
//! refused with the fix.

use crate::cli::{bearingd, stderr};
use crate::learned::{names_fresh_records_of_each_class, replayed_opinions};
use bearingd::bearing::BearingGeometry;
use bearingd::learned::ModelSet;
use bearingd::messages::FaultKind;
use bearingd_testdata::{repo_root, scratch_dir};
use std::path::Path;

/// A data-set spec as a TOML table that compares by meaning: its `bearing` replaced when
/// `bearing` is given, numbers as floats (`12000` and `12000.0` are one rate), and the default
/// `nuisance = false` as if absent (`dataset --bearing` writes the spec out in full).
fn spec_table(text: &str, bearing: Option<&str>) -> toml::Table {
    fn as_float(value: toml::Value) -> toml::Value {
        match value {
            toml::Value::Integer(i) => toml::Value::Float(i as f64),
            toml::Value::Array(items) => {
                toml::Value::Array(items.into_iter().map(as_float).collect())
            }
            other => other,
        }
    }
    let mut table: toml::Table = text
        .parse::<toml::Table>()
        .unwrap()
        .into_iter()
        .filter(|(key, value)| !(key == "nuisance" && value.as_bool() == Some(false)))
        .map(|(key, value)| (key, as_float(value)))
        .collect();
    if let Some(bearing) = bearing {
        table.insert("bearing".into(), toml::Value::String(bearing.into()));
    }
    table
}

#[test]
fn every_catalog_bearing_has_a_shipped_model_made_by_the_training_specs_that_names_fresh_records_of_it(
) {
    let models = ModelSet::load(&repo_root().join("models")).unwrap();
    let specs = [
        "config/learned-train.toml",
        "config/learned-train-physics.toml",
    ]
    .map(|spec| std::fs::read_to_string(repo_root().join(spec)).unwrap());
    for name in BearingGeometry::catalog_names() {
        let geometry = BearingGeometry::from_catalog(name).unwrap();
        let model = models.for_bearing(&geometry).unwrap();
        assert!(
            model.card.features.axis.is_shaft(),
            "{name}: {}",
            model.file
        );
        assert_eq!(model.card.bearing, name, "{}", model.file);
        assert!(
            model.file.ends_with(&format!("{name}.safetensors")),
            "{name}: {}",
            model.file
        );
        // scripts/train_model.sh OUT NAME: both specs with the bearing replaced, 30 epochs,
        // seed 1 (CI retrains the 6205's and checks it is the same model).
        let parts: Vec<toml::Table> = model
            .card
            .training
            .dataset_spec
            .split("# --- next data set ---")
            .map(|part| spec_table(part, None))
            .collect();
        let made_by: Vec<toml::Table> = specs.iter().map(|s| spec_table(s, Some(name))).collect();
        assert_eq!(parts, made_by, "{name}: {}", model.file);
        assert_eq!(
            (model.card.training.epochs, model.card.training.seed),
            (30, 1),
            "{name}"
        );
        names_fresh_records_of_each_class(model, &geometry);
    }
}

/// `bearingd validate CONFIG` with sensors of `bearings` and `learned_model = models`.
fn validate(dir: &Path, bearings: &[&str], models: &Path) -> std::process::Output {
    let mut text = String::new();
    for (i, bearing) in bearings.iter().enumerate() {
        text.push_str(&format!(
            "[[sensors]]\nid = \"s{i}\"\ntransport = \"sim\"\nsample_rate_hz = 12000\nbearing = \"{bearing}\"\n[sensors.speed]\nsource = \"fixed\"\nrpm = 1800\n"
        ));
    }
    text.push_str(&format!(
        "[twin]\nlearned_model = \"{}\"\n",
        models.display()
    ));
    let config = dir.join("config.toml");
    std::fs::write(&config, text).unwrap();
    bearingd(&["validate", config.to_str().unwrap()])
}

#[test]
fn a_model_directory_serves_sensors_of_several_bearings_and_is_refused_with_the_fix_when_it_cannot()
{
    let dir = scratch_dir("learned-model-dirs");
    let shipped = repo_root().join("models");
    let ok = validate(&dir, &["skf-6205-2rs", "skf-6203-2rs", "ims"], &shipped);
    assert!(ok.status.success(), "{}", stderr(&ok));

    let only_6205 = dir.join("only-6205");
    std::fs::create_dir_all(&only_6205).unwrap();
    std::fs::copy(
        shipped.join("skf-6205-2rs.safetensors"),
        only_6205.join("skf-6205-2rs.safetensors"),
    )
    .unwrap();
    let out = validate(&dir, &["skf-6205-2rs", "skf-6203-2rs"], &only_6205);
    let err = stderr(&out);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("sensor s1")
            && err.contains("no model for bearing skf-6203-2rs")
            && err.contains("it has models for: skf-6205-2rs")
            && err.contains("scripts/train_model.sh")
            && !err.contains("sensor s0"),
        "{err}"
    );

    std::fs::copy(
        shipped.join("skf-6205-2rs.safetensors"),
        only_6205.join("copy.safetensors"),
    )
    .unwrap();
    let out = validate(&dir, &["skf-6205-2rs"], &only_6205);
    let err = stderr(&out);
    assert!(
        !out.status.success() && err.contains("are both for bearing skf-6205-2rs"),
        "{err}"
    );

    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let out = validate(&dir, &["skf-6205-2rs"], &empty);
    let err = stderr(&out);
    assert!(
        !out.status.success() && err.contains("holds no *.safetensors file"),
        "{err}"
    );
}

/// The daemon, given the directory, judges a 6203's signal by the 6203's model.
#[test]
fn the_daemon_judges_each_signal_by_the_model_of_its_bearing() {
    let opinions = replayed_opinions(
        "learned-daemon-6203",
        "skf-6203-2rs",
        &repo_root().join("models"),
    );
    for opinion in &opinions {
        assert_eq!(
            opinion.probabilities[0].fault,
            Some(FaultKind::OuterRace),
            "{opinion:?}"
        );
    }
}

/// `analyze --learned models/` picks the record's bearing's model.
#[test]
fn analyze_with_the_model_directory_asks_the_model_of_the_records_bearing() {
    for bearing in ["skf-6203-2rs", "mfpt"] {
        let out = bearingd(&[
            "analyze",
            "--demo",
            "--bearing",
            bearing,
            "--learned",
            repo_root().join("models").to_str().unwrap(),
            "--format",
            "json",
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let opinion = &json["learned"]["opinion"];
        assert!(
            opinion["model"]
                .as_str()
                .is_some_and(|m| m.ends_with(&format!("{bearing}.safetensors")))
                && opinion["segments"].as_u64().is_some_and(|n| n > 0),
            "{json}"
        );
    }
}
