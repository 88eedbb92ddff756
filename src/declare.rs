//! Declarations of the scene's node kinds: each sdf node type, emitter type and material type states
//! its fields once, beside its own code ([`Kind`]), and everything that reads, lists, writes back or
//! checks those fields works from that one declaration: the scene parser, the parameter registry
//! ([`crate::scene::Scene::parameters`]), the write-back of values into the scene JSON, validation of
//! the file and of parameter updates (`--set`).
//!
//! A field has a kind (number, point, colour, pair, unit direction, fixed point, rotation, child node,
//! list of child nodes, file), an optional default (used when the file leaves it out, and not written
//! back while the value equals it) and a range rule. Numbers, points, colours, pairs and the rotation's
//! angle are differentiable parameters, named `<prefix>.<field>` (`.x/.y/.z`, `.r/.g/.b` for vector
//! components); unit directions and fixed points are not (see [`crate::scene::Scene::parameters`]).
//!
//! The accessors are plain function pointers, so a declaration is a `const` table; [`on!`] writes the
//! two accessors of a field (shared and mutable) from one pattern.

use crate::error::{Error, FieldPath};
use crate::scalar::{Param, Param3};
use std::path::Path;

/// A kind of scene node: its `type` name in the scene file and its fields, in the order the file's
/// error messages list them and the parameter registry names them.
pub struct Kind<N: 'static> {
    /// The value of the node's `type` key.
    pub type_name: &'static str,
    /// The node's fields, in order.
    pub fields: &'static [Field<N>],
    /// A node of this kind with placeholder values, which reading the file fills in field by field.
    pub blank: fn() -> N,
    /// A valid node of this kind as scene JSON, with every field given (the tests that walk every
    /// declared kind build their scenes from it; a grid file it names is written by them).
    pub example: &'static str,
}

/// One field of a node kind.
pub struct Field<N: 'static> {
    /// The key in the scene file, and the field's part of parameter names.
    pub key: &'static str,
    /// What the field holds, how to reach it, its default and its rule.
    pub value: Value<N>,
}

impl<N> Field<N> {
    /// A number with its default (`None`: required) and rule.
    pub const fn number(
        key: &'static str,
        access: Access<N, Param>,
        default: Option<f32>,
        rule: Rule<N>,
    ) -> Self {
        Self {
            key,
            value: Value::Number {
                access,
                default,
                rule,
            },
        }
    }

    /// Three numbers with their components' names, default (`None`: required) and rule.
    pub const fn vector(
        key: &'static str,
        access: Access<N, Param3>,
        components: Components,
        default: Option<f32>,
        rule: Rule<N>,
    ) -> Self {
        Self {
            key,
            value: Value::Vector {
                access,
                components,
                default,
                rule,
            },
        }
    }

    /// A required point `[x, y, z]`, any finite values.
    pub const fn point(key: &'static str, access: Access<N, Param3>) -> Self {
        Self::vector(key, access, Components::Xyz, None, Rule::Any)
    }

    /// A required unit direction, checked only for being non-zero.
    pub const fn direction(key: &'static str, access: Access<N, glam::Vec3>) -> Self {
        Self {
            key,
            value: Value::Direction {
                access,
                after: None,
            },
        }
    }
}

/// Shared and mutable access to one field of type `T` of a node of type `N` (see [`on!`]).
pub struct Access<N: 'static, T: 'static> {
    /// The field, read-only.
    pub get: fn(&N) -> &T,
    /// The field, to set it.
    pub get_mut: fn(&mut N) -> &mut T,
}

/// Component names of a vector parameter.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Components {
    /// A point or vector: `x, y, z`.
    Xyz,
    /// A linear RGB colour: `r, g, b`.
    Rgb,
}

impl Components {
    /// The three suffixes.
    pub fn names(self) -> &'static [&'static str; 3] {
        match self {
            Components::Xyz => &crate::error::XYZ,
            Components::Rgb => &crate::error::RGB,
        }
    }
}

/// A check of a field just read, which may adjust it and look at the fields read before it: the
/// message of a broken rule.
pub type Adjust<N> = fn(&mut N) -> Result<(), String>;

/// A check of a field just read, which may look at the fields read before it: the message of a broken
/// rule.
pub type Check<N> = fn(&N) -> Result<(), String>;

/// Component names of a pair ([`Value::Pair`]).
pub const PAIR: [&str; 2] = ["x", "y"];

/// What a field holds.
pub enum Value<N: 'static> {
    /// A number: parameter `<prefix>.<key>`.
    Number {
        /// The field.
        access: Access<N, Param>,
        /// Value when the file leaves the field out (`None`: required).
        default: Option<f32>,
        /// The range rule.
        rule: Rule<N>,
    },
    /// Three numbers (an array in the file): parameters `<prefix>.<key>.<component>`. A broken rule is
    /// reported once for the whole array in the file and per component as parameters.
    Vector {
        /// The field.
        access: Access<N, Param3>,
        /// Names of the components.
        components: Components,
        /// Every component's value when the file leaves the field out (`None`: required).
        default: Option<f32>,
        /// The range rule, per component.
        rule: Rule<N>,
    },
    /// Two numbers (an array in the file, such as a rectangle's `size`): parameters
    /// `<prefix>.<key>.x|y`, each element checked and reported on its own.
    Pair {
        /// The field.
        access: Access<N, [Param; 2]>,
        /// The range rule, per element.
        rule: Rule<N>,
    },
    /// A unit direction (normalised on input; a zero vector is an error). Not a parameter.
    Direction {
        /// The field.
        access: Access<N, glam::Vec3>,
        /// A check (or adjustment) after reading, which may look at the fields read before this one:
        /// the message of a broken rule.
        after: Option<Adjust<N>>,
    },
    /// A point that is not a parameter (a grid's box).
    Fixed {
        /// The field.
        access: Access<N, glam::Vec3>,
        /// A check after reading, which may look at the fields read before this one: the message of a
        /// broken rule.
        after: Option<Check<N>>,
    },
    /// A rotation `{"axis": [x, y, z], "angle": degrees}`, by default none (the angle 0 about `+y`):
    /// the angle is parameter `<prefix>.angle` (an sdf transform's) or `<prefix>.<key>.angle` (when
    /// `keyed`: an environment map's), the axis a unit direction.
    Rotation {
        /// The unit axis.
        axis: Access<N, glam::Vec3>,
        /// The angle in degrees.
        angle: Access<N, Param>,
        /// Whether the parameter's name holds the field's key.
        keyed: bool,
    },
    /// One child node, with prefix `<prefix>.<key>` unless named.
    Child(Access<N, N>),
    /// A non-empty list of child nodes, with prefixes `<prefix>.<key>.<i>` unless named.
    Children {
        /// The list.
        access: Access<N, Vec<N>>,
        /// The exact number of children the kind takes (`None`: any number from one).
        count: Option<usize>,
    },
    /// A file, named relative to the scene file's folder, read into the node once its other fields
    /// are read and valid (a file can be large).
    File {
        /// Reads the file into the node; the error message (the caller adds the field and the file).
        load: fn(&mut N, &Path) -> Result<(), String>,
    },
}

/// The range rule of a number or of each component of a vector.
pub enum Rule<N: 'static> {
    /// Any finite number.
    Any,
    /// `> 0`.
    Positive,
    /// `>= 0`.
    NonNegative,
    /// In `[0, 1]`.
    UnitInterval,
    /// A rule that relates the field to other fields of the node; checked after every rule of the
    /// kinds above, so that a broken field it depends on is reported first.
    Relation {
        /// Whether `value` is allowed in `node`.
        ok: fn(&N, f32) -> bool,
        /// The rule as stated in the error (`must be > minor_radius (0.25)`).
        text: fn(&N) -> String,
    },
}

impl<N> Rule<N> {
    /// Whether `v` satisfies the rule in `node`.
    pub fn allows(&self, node: &N, v: f32) -> bool {
        match self {
            Rule::Any => true,
            Rule::Positive => v > 0.0,
            Rule::NonNegative => v >= 0.0,
            Rule::UnitInterval => (0.0..=1.0).contains(&v),
            Rule::Relation { ok, .. } => ok(node, v),
        }
    }

    /// The rule as stated in an error message.
    pub fn text(&self, node: &N) -> String {
        match self {
            Rule::Any => "must be finite".into(),
            Rule::Positive => "must be > 0".into(),
            Rule::NonNegative => "must be >= 0".into(),
            Rule::UnitInterval => "must be in [0, 1]".into(),
            Rule::Relation { text, .. } => text(node),
        }
    }

    fn is_relation(&self) -> bool {
        matches!(self, Rule::Relation { .. })
    }
}

/// The two accessors of a field ([`Access`]) from one pattern that binds it: `on!(Sdf::Sphere { radius,
/// .. } => radius)` for a field of an enum variant (the pattern must match every node of the kind, which
/// is why the other arm is unreachable), `on!(Capsule { radius, .. } => radius)` for a struct's.
#[macro_export]
#[doc(hidden)]
macro_rules! on {
    ($pat:pat => $field:expr) => {
        $crate::declare::Access {
            get: |node| match node {
                $pat => $field,
                #[allow(unreachable_patterns)]
                _ => unreachable!("a declaration's accessor applied to another kind"),
            },
            get_mut: |node| match node {
                $pat => $field,
                #[allow(unreachable_patterns)]
                _ => unreachable!("a declaration's accessor applied to another kind"),
            },
        }
    };
}
pub use on;

/// A family of node kinds (sdf nodes, emitters, materials): every node knows its kind.
pub trait Family: Sized + 'static {
    /// The kinds, in the order the file's error messages list them.
    fn kinds() -> &'static [&'static Kind<Self>];
    /// This node's kind (for a named sdf node, the kind of the node it names).
    fn kind(&self) -> &'static Kind<Self>;
    /// The name and the node it names, when this node is only a name (sdf nodes named in the file).
    fn named(&self) -> Option<(&str, &Self)> {
        None
    }
    /// [`Family::named`] with mutable access to the named node.
    fn named_mut(&mut self) -> Option<(&str, &mut Self)> {
        None
    }
}

/// The kind of family `N` whose `type` is `name`.
pub fn kind_named<N: Family>(name: &str) -> Option<&'static Kind<N>> {
    N::kinds().iter().copied().find(|k| k.type_name == name)
}

/// The `type` names of family `N`, in order.
pub fn type_names<N: Family>() -> Vec<&'static str> {
    N::kinds().iter().map(|k| k.type_name).collect()
}

/// Generates the walks over a tree of nodes and the visits of a node's own parameters, for shared
/// or mutable access (the same walk written once, so that listing and setting parameters use the same
/// names by construction).
macro_rules! walks {
    ($walk:ident, $params:ident, $get:ident, $named:ident $(, $m:tt)?) => {
        /// Calls `f(prefix, node)` for `node` and every node below it, depth-first in field order: a
        /// child's prefix is `<prefix>.<key>` (`<prefix>.<key>.<i>` in a list), a named node's its
        /// name (and the name itself is not visited).
        pub fn $walk<N: Family>(node: &$($m)? N, prefix: &str, f: &mut dyn FnMut(&str, &$($m)? N)) {
            // Two steps so that the borrow of the name ends before the unnamed case.
            if node.named().is_some() {
                let (name, inner) = node.$named().expect("checked");
                let name = name.to_string();
                return $walk(inner, &name, f);
            }
            f(prefix, node);
            for field in node.kind().fields {
                match &field.value {
                    Value::Child(access) => {
                        let child = (access.$get)(node);
                        $walk(child, &format!("{prefix}.{}", field.key), f);
                    }
                    Value::Children { access, .. } => {
                        let children = (access.$get)(node);
                        for (i, c) in IntoIterator::into_iter(children).enumerate() {
                            $walk(c, &format!("{prefix}.{}.{i}", field.key), f);
                        }
                    }
                    _ => {}
                }
            }
        }

        /// Calls `f(name, parameter)` for the node's own parameters (not its children's), named
        /// under `prefix`, in field order.
        pub fn $params<N: Family>(node: &$($m)? N, prefix: &str, f: &mut dyn FnMut(&str, &$($m)? Param)) {
            for field in node.kind().fields {
                let key = field.key;
                match &field.value {
                    Value::Number { access, .. } => f(&format!("{prefix}.{key}"), (access.$get)(node)),
                    Value::Vector { access, components, .. } => {
                        let v = (access.$get)(node);
                        for (c, p) in components.names().iter().zip(& $($m)? v.c) {
                            f(&format!("{prefix}.{key}.{c}"), p);
                        }
                    }
                    Value::Pair { access, .. } => {
                        let v = (access.$get)(node);
                        for (c, p) in PAIR.iter().zip(v) {
                            f(&format!("{prefix}.{key}.{c}"), p);
                        }
                    }
                    Value::Rotation { angle, keyed, .. } => {
                        f(&rotation_angle_name(prefix, key, *keyed), (angle.$get)(node))
                    }
                    Value::Direction { .. }
                    | Value::Fixed { .. }
                    | Value::Child(_)
                    | Value::Children { .. }
                    | Value::File { .. } => {}
                }
            }
        }
    };
}

/// The parameter name of a rotation's angle ([`Value::Rotation`]) under `prefix`.
pub fn rotation_angle_name(prefix: &str, key: &str, keyed: bool) -> String {
    if keyed {
        format!("{prefix}.{key}.angle")
    } else {
        format!("{prefix}.angle")
    }
}

walks!(walk, own_params, get, named);
walks!(walk_mut, own_params_mut, get_mut, named_mut, mut);

/// Calls `f(name, parameter)` for every parameter of `node` and the nodes below it (see [`walk`] for
/// the prefixes).
pub fn params<N: Family>(node: &N, prefix: &str, f: &mut dyn FnMut(&str, &Param)) {
    walk(node, prefix, &mut |p, n| own_params(n, p, f));
}

/// [`params`] with mutable access.
pub fn params_mut<N: Family>(node: &mut N, prefix: &str, f: &mut dyn FnMut(&str, &mut Param)) {
    walk_mut(node, prefix, &mut |p, n| own_params_mut(n, p, f));
}

/// The broken rules of the node's own fields (not its children's), named by `at`, in a fixed order:
/// the rules on single fields in field order, then the relations ([`Rule::Relation`]). Empty when
/// the node is valid, and for a name ([`Family::named`]).
pub fn violations<N: Family>(node: &N, at: FieldPath) -> Vec<Error> {
    let mut out = Vec::new();
    if node.named().is_some() {
        return out;
    }
    for relations in [false, true] {
        for field in node.kind().fields {
            let key = field.key;
            match &field.value {
                Value::Number { access, rule, .. } if rule.is_relation() == relations => {
                    let v = (access.get)(node).value;
                    let ok = rule.allows(node, v);
                    at.check(&mut out, ok, at.field(key), &rule.text(node), v);
                }
                Value::Vector {
                    access,
                    components,
                    rule,
                    ..
                } if rule.is_relation() == relations && !matches!(rule, Rule::Any) => {
                    let v = (access.get)(node).value();
                    let ok = |x: f32| rule.allows(node, x);
                    at.check_each(&mut out, key, components.names(), v, ok, &rule.text(node));
                }
                Value::Pair { access, rule } if rule.is_relation() == relations => {
                    for (i, p) in (access.get)(node).iter().enumerate() {
                        let ok = rule.allows(node, p.value);
                        let field = at.element(key, i, &PAIR);
                        at.check(&mut out, ok, field, &rule.text(node), p.value);
                    }
                }
                _ => {}
            }
        }
    }
    out
}
