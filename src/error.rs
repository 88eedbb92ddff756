//! The library's error type: what went wrong and where (a field path or a file), in one line.

/// An error the library reports to its caller. `Display` is one line naming the field or file.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene value is missing, malformed or out of range. `field` is a path such as
    /// `shapes[2].sdf.radius`.
    #[error("{field}: {message}")]
    Field {
        /// Path of the offending field in the scene description.
        field: String,
        /// What is wrong with it, including the offending value.
        message: String,
    },
    /// A file could not be read, written or understood.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// A request that the renderer cannot honour (e.g. an option combination).
    #[error("{0}")]
    Unsupported(String),
}

impl Error {
    /// A field error.
    pub fn field(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Field {
            field: field.into(),
            message: message.into(),
        }
    }
    /// A file error.
    pub fn file(path: impl AsRef<std::path::Path>, message: impl std::fmt::Display) -> Self {
        Self::File {
            path: path.as_ref().display().to_string(),
            message: message.to_string(),
        }
    }
}

/// Result with the library's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Where the fields of one scene object are named in errors, and how a broken rule on a vector is
/// reported.
///
/// The scene file and the parameter registry name the same values differently: the file by JSON path
/// (`shapes[2].sdf.radius`, an array element `emitters[0].size[1]`), the registry by parameter name
/// (`ball.radius`, `key.size.y`). A vector is one field in the file, so its rule is reported once with
/// the whole value; it is three parameters in the registry, so each broken component is reported under
/// the name that was set. The rules themselves are written once, on the types (`validate` of
/// [`crate::sdf::Sdf`], [`crate::emitter::Emitter`] and [`crate::bsdf::Bsdf`]).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum FieldPath<'a> {
    /// JSON path of the object in the scene file, such as `shapes[2].sdf`.
    Json(&'a str),
    /// Parameter-name prefix of the object, such as `ball` (see [`crate::scene::Scene::parameters`]).
    Param(&'a str),
}

impl FieldPath<'_> {
    /// The name of field `key` of the object.
    pub fn field(&self, key: &str) -> String {
        match self {
            FieldPath::Json("") => key.to_string(),
            FieldPath::Json(p) | FieldPath::Param(p) => format!("{p}.{key}"),
        }
    }

    /// The name of element `i` of the array field `key`: `key[i]` in the file, `key.<names[i]>` as a
    /// parameter (`names` are the component suffixes, `x y z` or `r g b`).
    pub fn element(&self, key: &str, i: usize, names: &[&str]) -> String {
        match self {
            FieldPath::Json(_) => format!("{}[{i}]", self.field(key)),
            FieldPath::Param(_) => format!("{}.{}", self.field(key), names[i]),
        }
    }

    /// Appends `<field>: <rule>, got <value>` to `out` unless `ok`.
    pub fn check(&self, out: &mut Vec<Error>, ok: bool, field: String, rule: &str, value: f32) {
        if !ok {
            out.push(Error::field(field, format!("{rule}, got {value}")));
        }
    }

    /// Appends the errors of vector field `key` (components named `names`) whose components must each
    /// satisfy `ok`: one `every component <rule>, got [x, y, z]` in the file, one `<rule>, got <c>` per
    /// broken component as parameters.
    pub fn check_each(
        &self,
        out: &mut Vec<Error>,
        key: &str,
        names: &[&str; 3],
        value: glam::Vec3,
        ok: impl Fn(f32) -> bool,
        rule: &str,
    ) {
        let c = value.to_array();
        match self {
            FieldPath::Json(_) => {
                if !c.iter().all(|&x| ok(x)) {
                    out.push(Error::field(
                        self.field(key),
                        format!("every component {rule}, got [{}, {}, {}]", c[0], c[1], c[2]),
                    ));
                }
            }
            FieldPath::Param(_) => {
                for (i, &x) in c.iter().enumerate() {
                    self.check(out, ok(x), self.element(key, i, names), rule, x);
                }
            }
        }
    }
}

/// Component suffixes of a point or vector parameter.
pub const XYZ: [&str; 3] = ["x", "y", "z"];
/// Component suffixes of a colour parameter.
pub const RGB: [&str; 3] = ["r", "g", "b"];
