//! Complete derivatives (interior + primary + secondary boundary terms) against central finite
//! differences with common random numbers on the example scenes, at reduced resolution (same cameras).
//!
//! Each test renders all its parameters in one `DualN` pass and checks, per parameter
//! ([`common::deriv::check_against_fd`]): the relative L2 error after a 5×5 box blur over the whole
//! image; the sums over the whole image, the silhouette ring and the smooth pixels (each relative to the
//! region's Σ|blurred FD|); the primary term zero off the ring; every channel of every term finite; and
//! that the interior term alone misses (so each test can fail).
//!
//! Bounds come from two runs with independent seeds (`PSDR_TEST_SEED` unset and `=1`: estimator and FD
//! both reseeded); the values are quoted next to each bound as `(seed 0, seed 1)`. The FD steps were
//! checked by rendering with `h` and `h/2` (same seed): the blurred relative L2 between the two is quoted
//! as "h/2" and is at the level of the FD's own seed-to-seed difference ("FD noise"), so truncation
//! error is negligible next to the noise.

mod common;

use common::deriv::*;
use implicit_psdr::integrator::IntegratorKind;

/// The default scene at 32×32: the sphere on the floor under the rectangle light.
///
/// The estimator's noise dominates the errors: blurred rel L2 between two estimator seeds 0.036–0.068
/// ("FD noise" and "h/2" below were measured at 1024 spp).
#[test]
fn sphere_floor() {
    let scene = scene_file("sphere_floor.json", 32, 32);
    let budget = Budget {
        spp: 64,
        primary: 100_000,
        secondary: 400_000,
        fd_spp: 512,
    };
    check_against_fd(
        "sphere_floor",
        &scene,
        &[
            Check {
                name: "ball.radius",
                h: 0.02,
                // L2 (0.045, 0.043), sums (0.024, 0.002); interior alone 0.34;
                // FD noise 0.012, h/2 0.013.
                l2: 0.1,
                sum: 0.05,
            },
            Check {
                name: "ball.center.x",
                h: 0.02,
                // L2 (0.034, 0.033), sums (0.005, 0.014); interior alone 0.31;
                // FD noise 0.016, h/2 0.012.
                l2: 0.07,
                sum: 0.03,
            },
            Check {
                name: "ball.center.y",
                h: 0.02,
                // L2 (0.054, 0.043), sums (0.047, 0.033); interior alone 0.16;
                // FD noise 0.016, h/2 0.011.
                l2: 0.11,
                sum: 0.1,
            },
            Check {
                name: "light.center.x",
                h: 0.05,
                // L2 (0.019, 0.027), sums (0.003, 0.009); interior alone 0.24;
                // FD noise 0.011, h/2 0.007.
                l2: 0.06,
                sum: 0.03,
            },
        ],
        budget,
        1,
    );
}

/// The environment-lit scene (constant sky, direct) at 32×24: a position and two radii.
#[test]
fn environment() {
    let scene = scene_file("environment.json", 32, 24);
    let budget = Budget {
        spp: 64,
        primary: 50_000,
        secondary: 200_000,
        fd_spp: 512,
    };
    check_against_fd(
        "environment",
        &scene,
        &[
            Check {
                name: "ball.center.x",
                h: 0.05,
                // L2 (0.18, 0.24), sums (0.04, 0.25): a small net change, interior and
                // primary nearly cancel (interior alone 3.0); FD noise 0.10, h/2 0.065 (1024 spp).
                l2: 0.5,
                sum: 0.5,
            },
            Check {
                name: "donut.minor_radius",
                h: 0.02,
                // L2 (0.15, 0.11), sums (0.048, 0.034); interior alone 2.9;
                // FD noise 0.10, h/2 0.073 (1024 spp).
                l2: 0.3,
                sum: 0.1,
            },
        ],
        budget,
        2,
    );
}

/// The baked grid at 32×24: its translation and the scale of its transform (the grid's own shape
/// parameter).
#[test]
fn grid() {
    let scene = scene_file("grid.json", 32, 24);
    let budget = Budget {
        spp: 32,
        primary: 50_000,
        secondary: 200_000,
        fd_spp: 512,
    };
    check_against_fd(
        "grid",
        &scene,
        &[
            Check {
                name: "baked_blob.translate.x",
                h: 0.02,
                // L2 (0.17, 0.24), sums (0.14, 0.075); interior alone 1.6;
                // FD noise 0.066, h/2 0.045 (48×36).
                l2: 0.5,
                sum: 0.3,
            },
            Check {
                name: "baked_blob.sdf.scale",
                h: 0.01,
                // L2 (0.19, 0.19), sums (0.22, 0.10); interior alone 1.4;
                // FD noise 0.058, h/2 0.043 (48×36).
                l2: 0.4,
                sum: 0.45,
            },
        ],
        budget,
        3,
    );
}

/// The CSG shapes of csg.json with the `direct` integrator, at 48×36: the smooth union's sphere radius
/// and blend `k`, the torus's minor radius and position. The hard `difference` (`bitten`) and its crease
/// edges are not moved by these parameters, and the key light is fixed, so its creases' shadows do not
/// move either.
#[test]
fn csg_direct() {
    let mut scene = scene_file("csg.json", 48, 36);
    scene.integrator = IntegratorKind::Direct;
    check_against_fd("csg_direct", &scene, &csg_checks(), csg_budget(), 4);
}

fn csg_checks() -> [Check; 4] {
    [
        Check {
            name: "blob_sphere.radius",
            h: 0.02,
            // L2 (0.16, 0.16), sums (0.12, 0.059); interior alone 1.7;
            // FD noise 0.094, h/2 0.064 (1024 spp).
            l2: 0.33,
            sum: 0.24,
        },
        Check {
            name: "blob.k",
            h: 0.02,
            // L2 (0.16, 0.24), sums (0.094, 0.23): a weak signal (Σ|FD| 4.4);
            // interior alone 0.58; FD noise 0.19, h/2 0.14 (1024 spp).
            l2: 0.5,
            sum: 0.47,
        },
        Check {
            name: "ring.sdf.child.minor_radius",
            h: 0.01,
            // L2 (0.15, 0.15), sums (0.050, 0.014); interior alone 2.0;
            // FD noise 0.15, h/2 0.12 (1024 spp).
            l2: 0.31,
            sum: 0.1,
        },
        Check {
            name: "ring.sdf.translate.x",
            h: 0.02,
            // L2 (0.31, 0.31), sums (0.091, 0.071); interior alone 2.0. Noise, not
            // bias: with 4× the samples everywhere L2 fell to (0.12, 0.15); FD noise 0.081, h/2 0.074.
            l2: 0.63,
            sum: 0.19,
        },
    ]
}

fn csg_budget() -> Budget {
    Budget {
        spp: 64,
        primary: 100_000,
        secondary: 400_000,
        fd_spp: 512,
    }
}

/// csg.json as it is (`path`, three bounces). The bounds are the direct variant's, not yet measured
/// against the path estimator (it refuses boundary terms today).
#[test]
#[ignore = "needs the path boundary terms (issue 4, in progress)"]
fn csg_path() {
    let scene = scene_file("csg.json", 48, 36);
    assert!(matches!(scene.integrator, IntegratorKind::Path { .. }));
    check_against_fd("csg_path", &scene, &csg_checks(), csg_budget(), 5);
}

/// The default scene with the `path` integrator (two bounces: the floor lights the ball's underside
/// and the ball's shadow lightens). Bounds provisional (the direct variant's order of magnitude): to be
/// set from two seeds once the path boundary terms land.
#[test]
#[ignore = "needs the path boundary terms (issue 4, in progress)"]
fn sphere_floor_path() {
    let mut scene = scene_file("sphere_floor.json", 32, 32);
    scene.integrator = IntegratorKind::Path { max_depth: 2 };
    let budget = Budget {
        spp: 64,
        primary: 100_000,
        secondary: 400_000,
        fd_spp: 512,
    };
    check_against_fd(
        "sphere_floor_path",
        &scene,
        &[
            Check {
                name: "ball.radius",
                h: 0.02,
                l2: 0.1,
                sum: 0.1,
            },
            Check {
                name: "light.center.x",
                h: 0.05,
                l2: 0.1,
                sum: 0.1,
            },
        ],
        budget,
        6,
    );
}
