//! Every declared node kind (sdf nodes, emitters, materials) through every consumer of its
//! declaration: the scene parser, the parameter registry, the write-back into the scene JSON and the
//! field rules (of the file and of parameter updates). The kinds are taken from the declarations
//! themselves, so a kind added later is covered without editing this test.

use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::declare::{Family, Kind, PAIR, Rule, Value};
use implicit_psdr::emitter::Emitter;
use implicit_psdr::scene::patch::{patched_scene_json, scene_text};
use implicit_psdr::scene::{Scene, parse};
use implicit_psdr::sdf::{GridData, Sdf, write_npy};
use serde_json::json;
use std::path::{Path, PathBuf};

/// A fresh folder for one test, holding the files the grid and envmap kinds' examples name.
fn workdir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("psdr-declarations-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // A ball of radius 0.6 sampled on 8³ points over [-1, 1]³ (a distance field).
    let n = 8;
    let values = (0..n * n * n)
        .map(|i| {
            let c = |k: usize| -1.0 + 2.0 * k as f32 / (n - 1) as f32;
            glam::Vec3::new(c(i % n), c(i / n % n), c(i / (n * n))).length() - 0.6
        })
        .collect();
    let grid = GridData::new([n, n, n], values, "test grid").unwrap();
    write_npy(&dir.join("example_grid.npy"), &grid).unwrap();
    // The envmap kind's example: a 4 × 2 map with a brighter texel.
    let plane = |v: f32| {
        (0..8)
            .map(|k| if k == 5 { 4.0 * v } else { v })
            .collect::<Vec<f32>>()
    };
    let channels = [("R", 0.5), ("G", 0.6), ("B", 0.8)].map(|(n, v)| (n.to_string(), plane(v)));
    implicit_psdr::io::write_exr(&dir.join("example_envmap.exr"), 4, 2, &channels).unwrap();
    dir
}

/// Which family a kind under test belongs to, and where its node sits in the test scene.
#[derive(Copy, Clone, Debug)]
enum Place {
    /// The sdf of shape `s`.
    Sdf,
    /// The material of shape `s`.
    Bsdf,
    /// The second emitter (after a sphere light).
    Emitter,
}

impl Place {
    /// A scene holding `example` at this place.
    fn scene(self, example: &serde_json::Value) -> serde_json::Value {
        let ball = json!({"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5});
        let diffuse = json!({"type": "diffuse", "albedo": [0.5, 0.5, 0.5]});
        let lamp = json!({"name": "lamp", "type": "sphere", "center": [2, 3, 1], "radius": 0.25,
                          "radiance": [9, 9, 9]});
        let (sdf, bsdf, emitters) = match self {
            Place::Sdf => (example.clone(), diffuse, json!([lamp])),
            Place::Bsdf => (ball, example.clone(), json!([lamp])),
            Place::Emitter => (ball, diffuse, json!([lamp, example.clone()])),
        };
        json!({
            "camera": {"origin": [0, 1.5, 4], "target": [0, 0.4, 0], "up": [0, 1, 0], "fov_y": 40,
                       "width": 8, "height": 8},
            "shapes": [{"name": "s", "sdf": sdf, "bsdf": bsdf}],
            "emitters": emitters
        })
    }

    /// The JSON path of the node in [`Place::scene`].
    fn path(self) -> &'static str {
        match self {
            Place::Sdf => "shapes[0].sdf",
            Place::Bsdf => "shapes[0].bsdf",
            Place::Emitter => "emitters[1]",
        }
    }
}

/// The parameter prefix of the node at `place` in `scene`.
fn prefix(place: Place, scene: &Scene, example: &serde_json::Value) -> String {
    match place {
        Place::Sdf => match (example.get("name"), scene.shapes[0].sdf.unnamed()) {
            (Some(name), _) => name.as_str().unwrap().to_string(),
            (None, Sdf::Transform { .. }) => "s.sdf".into(),
            (None, _) => "s".into(),
        },
        Place::Bsdf => "s".into(),
        Place::Emitter => example["name"].as_str().unwrap().to_string(),
    }
}

/// The parameter names of a node's own fields as its declaration states them.
fn declared_parameters<N>(kind: &Kind<N>, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    for field in kind.fields {
        let key = field.key;
        match &field.value {
            Value::Number { .. } => out.push(format!("{prefix}.{key}")),
            Value::Vector { components, .. } => {
                (components.names().iter()).for_each(|c| out.push(format!("{prefix}.{key}.{c}")))
            }
            Value::Pair { .. } => PAIR
                .iter()
                .for_each(|c| out.push(format!("{prefix}.{key}.{c}"))),
            Value::Rotation { keyed: false, .. } => out.push(format!("{prefix}.angle")),
            Value::Rotation { keyed: true, .. } => out.push(format!("{prefix}.{key}.angle")),
            _ => {}
        }
    }
    out
}

/// Values that break `rule` in `node`, if the rule can be broken by a finite number.
fn bad_value<N>(rule: &Rule<N>, node: &N) -> Option<f32> {
    [-1.0, 0.0, 2.0, -1e6, 1e6]
        .into_iter()
        .find(|&v| !rule.allows(node, v))
}

/// Every parameter of the re-parsed scene equals the written one, bit for bit, in the same order.
#[track_caller]
fn assert_same_parameters(got: &Scene, want: &Scene, what: &str) {
    let (got, want) = (got.parameters(), want.parameters());
    assert_eq!(got.len(), want.len(), "{what}");
    for ((n, a), (m, b)) in got.iter().zip(&want) {
        assert_eq!(n, m, "{what}");
        assert_eq!(a.to_bits(), b.to_bits(), "{what}: {n}: {a} vs {b}");
    }
}

/// Every check on one kind; `node` picks the parsed node of the kind out of the scene.
fn check_kind<N: Family>(kind: &Kind<N>, place: Place, dir: &Path, node: fn(&Scene) -> &N) {
    let what = format!("{:?} kind {:?}", place, kind.type_name);
    let example: serde_json::Value = serde_json::from_str(kind.example)
        .unwrap_or_else(|e| panic!("{what}: the example is not JSON: {e}"));
    assert_eq!(example["type"], kind.type_name, "{what}");
    let doc = place.scene(&example);
    let scene = parse(&doc.to_string(), dir).unwrap_or_else(|e| panic!("{what}: {e}"));
    let prefix = prefix(place, &scene, &example);

    // Every declared parameter is listed.
    let names: Vec<String> = scene.parameters().into_iter().map(|(n, _)| n).collect();
    let declared = declared_parameters(kind, &prefix);
    for name in &declared {
        assert!(names.contains(name), "{what}: {name} not in {names:?}");
    }

    // Parse → write back → parse gives the same scene, unchanged and with every value changed.
    let same = patched_scene_json(&doc, &scene, &[]).unwrap();
    let back = parse(&scene_text(&same), dir).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(back, scene, "{what}: written back unchanged");
    let mut changed = scene.clone();
    changed.visit_params_mut(&mut |name, p| {
        if !name.starts_with("camera.up.") {
            p.value = 1.01 * p.value + 0.003;
        }
    });
    let doc2 = patched_scene_json(&doc, &changed, &[]).unwrap();
    let back = parse(&scene_text(&doc2), dir).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_same_parameters(&back, &changed, &what);

    // Every field with a rule rejects a bad value, in the file and as a parameter, naming it.
    let own = node(&scene);
    for field in kind.fields {
        let key = field.key;
        let (rule, components): (&Rule<N>, Vec<String>) = match &field.value {
            Value::Number { rule, .. } => (rule, vec![String::new()]),
            Value::Vector {
                rule, components, ..
            } => (rule, components.names().map(|c| format!(".{c}")).to_vec()),
            Value::Pair { rule, .. } => (rule, PAIR.map(|c| format!(".{c}")).to_vec()),
            _ => continue,
        };
        for (i, suffix) in components.iter().enumerate() {
            let name = format!("{prefix}.{key}{suffix}");
            let e = scene
                .with_parameter(&name, f32::NAN)
                .unwrap_err()
                .to_string();
            assert!(e.starts_with(&format!("{name}: ")), "{what}: {e}");
            let Some(bad) = bad_value(rule, own) else {
                // A relation on the whole vector (a sun's direction must not be zero) may have no
                // bad value for one component alone; its kind's own tests cover it.
                assert!(
                    matches!(rule, Rule::Any | Rule::Relation { .. }),
                    "{what}: {key} has no bad value"
                );
                continue;
            };
            let e = scene.with_parameter(&name, bad).unwrap_err().to_string();
            assert!(e.starts_with(&format!("{name}: must")), "{what}: {e}");
            // The same value in the file.
            let mut bad_doc = doc.clone();
            let at = match place {
                Place::Sdf => &mut bad_doc["shapes"][0]["sdf"],
                Place::Bsdf => &mut bad_doc["shapes"][0]["bsdf"],
                Place::Emitter => &mut bad_doc["emitters"][1],
            };
            match suffix.is_empty() {
                true => at[key] = json!(bad),
                false => at[key][i] = json!(bad),
            }
            let e = parse(&bad_doc.to_string(), dir).unwrap_err().to_string();
            let field_path = format!("{}.{key}", place.path());
            assert!(e.starts_with(&field_path), "{what}: {e}");
            assert!(e.contains("must"), "{what}: {e}");
        }
    }
}

#[test]
fn every_declared_kind_parses_lists_writes_back_and_checks_its_fields() {
    let dir = workdir("every-kind");
    assert!(!Sdf::kinds().is_empty() && !Emitter::kinds().is_empty() && !Bsdf::kinds().is_empty());
    for kind in Sdf::kinds() {
        check_kind(kind, Place::Sdf, &dir, |s| s.shapes[0].sdf.unnamed());
    }
    for kind in Bsdf::kinds() {
        check_kind(kind, Place::Bsdf, &dir, |s| &s.shapes[0].bsdf);
    }
    for kind in Emitter::kinds() {
        check_kind(kind, Place::Emitter, &dir, |s| &s.emitters[1].emitter);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unknown_types_list_the_declared_kinds() {
    let dir = workdir("unknown-type");
    let doc = Place::Sdf.scene(&json!({"type": "spere", "center": [0, 0, 0], "radius": 1}));
    let e = parse(&doc.to_string(), &dir).unwrap_err().to_string();
    let names: Vec<&str> = Sdf::kinds().iter().map(|k| k.type_name).collect();
    assert_eq!(
        e,
        format!(
            "shapes[0].sdf.type: unknown type \"spere\", expected one of {}",
            names.join(", ")
        )
    );
    let _ = std::fs::remove_dir_all(&dir);
}
