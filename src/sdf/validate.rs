//! The scene rules on a node's own fields (a radius `> 0`, a rounding within the half sizes, ...), as
//! declared with each node kind, used by the scene parser and by parameter updates alike, so the two
//! cannot drift apart.

use super::Sdf;
use crate::error::{Error, FieldPath};

impl Sdf {
    /// The broken rules of this node's own fields, named by `at` (the node's path or parameter prefix),
    /// in a fixed order (rules on one field in field order, then rules relating fields); empty when the
    /// node is valid. Children are not visited: the parser checks each node as it reads it and the
    /// parameter registry walks the tree with its own naming. The rules are the node kind's declaration
    /// ([`crate::declare::Kind`]).
    ///
    /// Unit directions and grids are checked where they are read (they are not parameters).
    pub fn validate(&self, at: FieldPath) -> Vec<Error> {
        crate::declare::violations(self, at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::{Param, Param3};

    fn messages(sdf: &Sdf, at: FieldPath) -> Vec<String> {
        sdf.validate(at).iter().map(Error::to_string).collect()
    }

    #[test]
    fn a_vector_rule_is_one_error_in_the_file_and_one_per_component_as_parameters() {
        let b = Sdf::Box {
            center: Param3::from(glam::Vec3::ZERO),
            half_size: Param3::from(glam::Vec3::new(1.0, -1.0, -2.0)),
            rounding: Param::new(0.0),
        };
        assert_eq!(
            messages(&b, FieldPath::Json("shapes[1].sdf")),
            ["shapes[1].sdf.half_size: every component must be > 0, got [1, -1, -2]"]
        );
        assert_eq!(
            messages(&b, FieldPath::Param("blob_box")),
            [
                "blob_box.half_size.y: must be > 0, got -1",
                "blob_box.half_size.z: must be > 0, got -2"
            ]
        );
    }

    #[test]
    fn rules_relating_two_fields_name_the_dependent_one() {
        let t = Sdf::Torus {
            center: Param3::from(glam::Vec3::ZERO),
            axis: glam::Vec3::Y,
            major_radius: Param::new(0.25),
            minor_radius: Param::new(0.25),
        };
        assert_eq!(
            messages(&t, FieldPath::Param("ring")),
            ["ring.major_radius: must be > minor_radius (0.25), got 0.25"]
        );
        let c = Sdf::Cylinder {
            center: Param3::from(glam::Vec3::ZERO),
            axis: glam::Vec3::Y,
            radius: Param::new(0.5),
            half_height: Param::new(2.0),
            rounding: Param::new(0.75),
        };
        assert_eq!(
            messages(&c, FieldPath::Json("")),
            ["rounding: must be in [0, 0.5], got 0.75"]
        );
    }

    #[test]
    fn children_are_not_visited() {
        let bad = Sdf::Sphere {
            center: Param3::from(glam::Vec3::ZERO),
            radius: Param::new(-1.0),
        };
        let union = Sdf::union(vec![bad.clone()]);
        assert!(union.validate(FieldPath::Json("s")).is_empty());
        assert_eq!(bad.validate(FieldPath::Json("s")).len(), 1);
    }
}
