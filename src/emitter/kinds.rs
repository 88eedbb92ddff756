//! The declarations of the emitter kinds ([`crate::declare`]): each kind's `type` name, fields, rules
//! and example, in the order the scene file's errors list them.

use super::{Emitter, EnvMap};
use crate::declare::{Components, Family, Field, Kind, Rule, Value, on};
use crate::scalar::{Param, Param3};
use std::sync::Arc;

/// Every emitter kind ([`crate::declare`]), in the order the scene file's errors list them.
const KINDS: &[&Kind<Emitter>] = &[
    &RECTANGLE,
    &SPHERE,
    &CONSTANT,
    &ENVMAP,
    &POINT,
    &DIRECTIONAL,
];

impl Family for Emitter {
    fn kinds() -> &'static [&'static Kind<Emitter>] {
        KINDS
    }

    fn kind(&self) -> &'static Kind<Emitter> {
        match self {
            Emitter::Rectangle { .. } => &RECTANGLE,
            Emitter::Sphere { .. } => &SPHERE,
            Emitter::Constant { .. } => &CONSTANT,
            Emitter::Envmap { .. } => &ENVMAP,
            Emitter::Point { .. } => &POINT,
            Emitter::Directional { .. } => &DIRECTIONAL,
        }
    }
}

/// An emitter's `radiance` (linear RGB, `>= 0`).
const fn radiance(access: crate::declare::Access<Emitter, Param3>) -> Field<Emitter> {
    colour("radiance", access)
}

/// A required colour field (linear RGB, `>= 0`).
const fn colour(
    key: &'static str,
    access: crate::declare::Access<Emitter, Param3>,
) -> Field<Emitter> {
    Field::vector(key, access, Components::Rgb, None, Rule::NonNegative)
}

fn zero3() -> Param3 {
    Param3::from(glam::Vec3::ZERO)
}

/// `{"type": "rectangle", "name", "center", "normal", "u", "size": [along u, along normal × u],
/// "radiance"}`.
const RECTANGLE: Kind<Emitter> = Kind {
    type_name: "rectangle",
    fields: &[
        Field::point("center", on!(Emitter::Rectangle { center, .. } => center)),
        Field::direction("normal", on!(Emitter::Rectangle { normal, .. } => normal)),
        Field {
            key: "u",
            value: Value::Direction {
                access: on!(Emitter::Rectangle { u, .. } => u),
                after: Some(in_rectangle_plane),
            },
        },
        Field {
            key: "size",
            value: Value::Pair {
                access: on!(Emitter::Rectangle { size, .. } => size),
                rule: Rule::Positive,
            },
        },
        radiance(on!(Emitter::Rectangle { radiance, .. } => radiance)),
    ],
    blank: || Emitter::Rectangle {
        center: zero3(),
        normal: glam::Vec3::Y,
        u: glam::Vec3::X,
        size: [Param::new(0.0), Param::new(0.0)],
        radiance: zero3(),
    },
    example: r#"{"type": "rectangle", "name": "example", "center": [0, 3, 0], "normal": [0, -1, 0], "u": [1, 0, 0], "size": [1, 0.5], "radiance": [5, 5, 5]}"#,
};

/// Gram–Schmidt: keeps the rectangle in the plane given by `normal`, with its first edge as close to
/// the given `u` as possible. A `u` within ~0.06° of the normal has no such direction.
fn in_rectangle_plane(e: &mut Emitter) -> Result<(), String> {
    let Emitter::Rectangle { normal, u, .. } = e else {
        unreachable!("a rectangle's rule")
    };
    let u_perp = *u - *normal * normal.dot(*u);
    match u_perp.try_normalize().filter(|_| u_perp.length() > 1e-3) {
        Some(v) => {
            *u = v;
            Ok(())
        }
        None => {
            let fmt = |v: glam::Vec3| format!("[{}, {}, {}]", v.x, v.y, v.z);
            Err(format!(
                "must not be parallel to normal {}, got {}",
                fmt(*normal),
                fmt(*u)
            ))
        }
    }
}

/// `{"type": "sphere", "name", "center", "radius", "radiance"}`.
const SPHERE: Kind<Emitter> = Kind {
    type_name: "sphere",
    fields: &[
        Field::point("center", on!(Emitter::Sphere { center, .. } => center)),
        Field::number(
            "radius",
            on!(Emitter::Sphere { radius, .. } => radius),
            None,
            Rule::Positive,
        ),
        radiance(on!(Emitter::Sphere { radiance, .. } => radiance)),
    ],
    blank: || Emitter::Sphere {
        center: zero3(),
        radius: Param::new(0.0),
        radiance: zero3(),
    },
    example: r#"{"type": "sphere", "name": "example", "center": [1.5, 3, 2], "radius": 0.3, "radiance": [30, 30, 30]}"#,
};

/// `{"type": "constant", "name", "radiance"}`: radiance arriving from every direction.
const CONSTANT: Kind<Emitter> = Kind {
    type_name: "constant",
    fields: &[radiance(on!(Emitter::Constant { radiance } => radiance))],
    blank: || Emitter::Constant { radiance: zero3() },
    example: r#"{"type": "constant", "name": "example", "radiance": [0.3, 0.3, 0.3]}"#,
};

/// `{"type": "envmap", "name", "file", "scale" (default 1), "rotate": {"axis", "angle"} (default
/// none)}`: radiance from a latitude–longitude RGB EXR ([`super::envmap`]), times `scale`, rotated
/// from the map's frame into the world by `rotate`.
const ENVMAP: Kind<Emitter> = Kind {
    type_name: "envmap",
    fields: &[
        Field {
            key: "file",
            value: Value::File { load: load_envmap },
        },
        Field::number(
            "scale",
            on!(Emitter::Envmap { scale, .. } => scale),
            Some(1.0),
            Rule::NonNegative,
        ),
        Field {
            key: "rotate",
            value: Value::Rotation {
                axis: on!(Emitter::Envmap { axis, .. } => axis),
                angle: on!(Emitter::Envmap { angle, .. } => angle),
                keyed: true,
            },
        },
    ],
    blank: || Emitter::Envmap {
        map: Arc::new(EnvMap::uniform([0.0; 3]).expect("a black texel is valid")),
        scale: Param::new(1.0),
        axis: glam::Vec3::Y,
        angle: Param::new(0.0),
    },
    example: r#"{"type": "envmap", "name": "example", "file": "example_envmap.exr", "scale": 0.8, "rotate": {"axis": [0, 1, 0], "angle": 30}}"#,
};

/// Reads an environment map's EXR into the node ([`EnvMap::read`]).
fn load_envmap(node: &mut Emitter, file: &std::path::Path) -> Result<(), String> {
    let map = EnvMap::read(file)?;
    let Emitter::Envmap { map: slot, .. } = node else {
        unreachable!("an envmap's file")
    };
    *slot = Arc::new(map);
    Ok(())
}

/// `{"type": "point", "name", "position", "intensity"}`: a point light of radiant intensity
/// `intensity` (W/sr) at `position`.
const POINT: Kind<Emitter> = Kind {
    type_name: "point",
    fields: &[
        Field::point("position", on!(Emitter::Point { position, .. } => position)),
        colour(
            "intensity",
            on!(Emitter::Point { intensity, .. } => intensity),
        ),
    ],
    blank: || Emitter::Point {
        position: zero3(),
        intensity: zero3(),
    },
    example: r#"{"type": "point", "name": "example", "position": [1, 3, 2], "intensity": [20, 20, 20]}"#,
};

/// `{"type": "directional", "name", "direction", "irradiance"}`: the sun, light travelling along
/// `direction` with `irradiance` (W/m²) on a surface facing it. The direction is a parameter (not
/// normalised in the file, so its components are the values `--set` and the derivatives see).
const DIRECTIONAL: Kind<Emitter> = Kind {
    type_name: "directional",
    fields: &[
        Field::vector(
            "direction",
            on!(Emitter::Directional { direction, .. } => direction),
            Components::Xyz,
            None,
            Rule::Relation {
                ok: |e, _| {
                    let Emitter::Directional { direction, .. } = e else {
                        unreachable!("a directional light's rule")
                    };
                    direction.value().try_normalize().is_some()
                },
                text: |_| "must be part of a non-zero direction".into(),
            },
        ),
        colour(
            "irradiance",
            on!(Emitter::Directional { irradiance, .. } => irradiance),
        ),
    ],
    blank: || Emitter::Directional {
        direction: zero3(),
        irradiance: zero3(),
    },
    example: r#"{"type": "directional", "name": "example", "direction": [-0.3, -1, -0.2], "irradiance": [2, 2, 2]}"#,
};
