//! Columns of boxes dropped on an auto-tool plate (issue 13: any body, several at once, two-way
//! coupling that creates no energy): a property test over columns nobody tuned, the cases its
//! random seeds found, and a column at rest.

use crate::auto_tools::{auto_plate, drop_box, stack_energy};
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(8))]

    /// Columns nobody tuned dropped on the plate: 1 to 4 boxes of 4 to 20 cm, 10 g to 1 kg
    /// each, one above the other with gaps of 0 to 50 cm, on plates of 60 to 6000 N/m, with
    /// and without friction (μ 0.5), 10 s ([`Column::drop`]). Checked until a box comes
    /// within its size of the plate's pinned rim: past it a box may leave the plate and fall
    /// below it (columns that topple on a frictionless plate slide there, CI's seed found one;
    /// a box sliding off the rim is `a_box_sliding_off_the_plates_edge_creates_no_energy`). The
    /// plate's own energy is left out: where a cube lands flat, the presses move the vertices
    /// under it to its face at once and the plate's elastic energy jumps for a step (random
    /// seed 13: 25 g, 4.2 cm, 844 N/m, the plate at 0.037 J with 0.029 J brought in), then
    /// its dampers take it. The cases random seeds found are kept
    /// (`the_columns_that_gained_energy_keep_it`).
    #[test]
    fn dropped_columns_of_boxes_create_no_energy(
        n in 1usize..5,
        log_half in -1.7f32..-1.0,
        log_mass in -2.0f32..0.0,
        log_k in 1.78f32..3.78,
        gap in 0.0f32..0.5,
        friction in proptest::prelude::any::<bool>(),
    ) {
        let column = Column::drawn(n, (log_half, log_mass, log_k), gap, friction);
        if let Err(e) = column.drop(600) {
            proptest::prop_assert!(false, "{}", e);
        }
    }
}

/// A column of `n` cubes of `half` half-extents and `mass` each, one above the other with
/// `gap` between them, the lowest 10 cm above the auto-tool plate of `stiffness` N/m, with
/// Coulomb friction (μ 0.5) on the boxes or none.
struct Column {
    n: usize,
    half: f32,
    mass: f32,
    stiffness: f32,
    gap: f32,
    friction: bool,
}

impl Column {
    /// The column of `n` boxes with the base-10 logarithms of their half-extents, mass and
    /// the plate's stiffness, as the property test draws them.
    fn drawn(
        n: usize,
        (log_half, log_mass, log_k): (f32, f32, f32),
        gap: f32,
        friction: bool,
    ) -> Self {
        Column {
            n,
            half: 10f32.powf(log_half),
            mass: 10f32.powf(log_mass),
            stiffness: 10f32.powf(log_k),
            gap,
            friction,
        }
    }

    /// Drops the column for up to `steps` steps: the boxes' energy (kinetic and their
    /// weight's potential) never rises above what they started with, and no box goes
    /// through the plate (checked until a box comes within its size of the plate's pinned
    /// rim). Returns the world, the set and the boxes at the end, or what failed.
    #[allow(clippy::type_complexity)]
    fn drop(
        &self,
        steps: usize,
    ) -> Result<
        (
            PhysicsWorld,
            SurfaceSet,
            Vec<(RigidBodyHandle, ColliderHandle)>,
        ),
        String,
    > {
        let half = self.half;
        let (mut world, mut set, h) = auto_plate();
        set.get_mut(h)
            .unwrap()
            .surface
            .set_spring(self.stiffness, 2.0)
            .unwrap();
        let boxes: Vec<(RigidBodyHandle, ColliderHandle)> = (0..self.n)
            .map(|i| {
                let y = 0.1 + half + i as f32 * (2.0 * half + self.gap);
                let cube = ColliderBuilder::cuboid(half, half, half);
                drop_box(&mut world, half, self.mass, y, cube)
            })
            .collect();
        let e0 = stack_energy(&world, &set, (h, false), &boxes);
        let inner = 0.5 - 2.0 * half;
        for step in 0..steps {
            let near_rim = boxes.iter().any(|(b, _)| {
                let p = world.bodies[*b].translation();
                p.x.abs() > inner || p.z.abs() > inner
            });
            if near_rim {
                break;
            }
            set.step(&mut world);
            if self.friction {
                for (_, c) in &boxes {
                    let _ = set.set_tool_friction(*c, Friction::new(0.5, 0.5).unwrap());
                }
            }
            let e = stack_energy(&world, &set, (h, false), &boxes);
            if e > e0 + 1e-6 * e0.abs().max(1e-3) {
                return Err(format!("step {step}: {e} J against {e0} J at the start"));
            }
            for (b, _) in &boxes {
                let p = world.bodies[*b].translation();
                let over = p.x.abs() < 0.45 && p.z.abs() < 0.45;
                if over && p.y < -0.5 {
                    return Err(format!("step {step}: a box through at {p:?}"));
                }
            }
        }
        Ok((world, set, boxes))
    }
}

/// The columns random seeds of `dropped_columns_of_boxes_create_no_energy` found gaining
/// energy, all with friction: three 45 g boxes of 4.1 cm dropped 35 cm apart on 2000 N/m
/// (seed 23: half their energy again, 1.05 J against 0.67 J, as the second landed on the
/// first), three 11 g boxes of 4.4 cm on 694 N/m (seed 8301: three times their energy at the
/// first landings), four 16 g boxes of 14.5 cm on 6000 N/m (seed 19, after the support's
/// fix below: the column stood wobbling for 7 s, then the bottom box was thrown at 9 km/s),
/// and two 21 g boxes of 4.2 cm dropped 37 cm apart on 1480 N/m (seed 105, with both fixes
/// below but the friction's last solve: the upper one, at 3.1 m/s, went 2.7 cm into the
/// lower in rapier's step, as in vanilla rapier without CCD, and rapier pushed the lower
/// down at 1.6 m/s; it left spinning at 260 rad/s; the code before passed it). The
/// cause: a dynamic tool's points held stuck by friction took impulses far past their
/// static limit in the solve's last pass (some with no normal load at all), the normal
/// pushes balancing them; cut to the limit after it, they left those pushes unbalanced. With
/// that fixed, four 12 g boxes of 12 cm dropped 23 cm apart on 6000 N/m (seed 50) still
/// reached 63 J from 0.32 J at step 320 while the support handed to rapier was the whole
/// impulse of the last step, which includes the impulse that stopped the box's own fall or
/// spin (on seed 23 a tumbling box was spun the other way at 290 rad/s by it).
#[test]
fn the_columns_that_gained_energy_keep_it() {
    let cases = [
        (3, -1.683_373_3, -1.347_522_3, 3.305_984_5, 0.348_246_5),
        (3, -1.658_675_2, -1.969_886_1, 2.841_504_8, 0.060_902_655),
        (4, -1.139_039, -1.783_346_2, 3.777_747_4, 0.229_394_9),
        (2, -1.672_666_8, -1.684_476_6, 3.170_174_1, 0.371_307_34),
        (4, -1.209_329_5, -1.932_485_9, 3.776_327_8, 0.229_778_36),
    ];
    for (n, log_half, log_mass, log_k, gap) in cases {
        let column = Column::drawn(n, (log_half, log_mass, log_k), gap, true);
        if let Err(e) = column.drop(600) {
            panic!("{n} boxes of 10^{log_half} m on 10^{log_k} N/m: {e}");
        }
    }
}

/// A column of four light boxes (16 g, 14.5 cm) dropped from 10 cm, stacked and 5 cm and
/// 23 cm apart, on a stiff plate (6000 N/m) with friction stands still: after 10 s no box
/// is more than 2 mm into the one below or moves faster than 1 cm/s or 0.05 rad/s. The
/// bottom box used to rock on its corners (up to 1.4 rad/s) and the box above sank 1 cm into
/// it (the friction solve's cut impulses, above); with the whole impulse of the last step as
/// the bottom box's support, the boxes above it kept moving (the second at 1.1 cm/s after
/// 10 s, stacked), where vanilla rapier's column on rigid ground is at rest. Without
/// friction nothing stops the column turning about the vertical where the landing set it
/// turning (0.02-0.2 rad/s), so that case is left to the energy test.
#[test]
fn a_column_of_light_boxes_on_a_stiff_plate_stands_still_with_friction() {
    for gap in [0.0, 0.05, 0.229] {
        let column = Column {
            n: 4,
            half: 0.0726,
            mass: 0.0165,
            stiffness: 6000.0,
            gap,
            friction: true,
        };
        let (world, _, boxes) = column.drop(600).unwrap();
        for (i, (b, _)) in boxes.iter().enumerate() {
            let r = &world.bodies[*b];
            let (v, w) = (r.linvel().length(), r.angvel().length());
            assert!(
                v < 0.01 && w < 0.05,
                "gap {gap}, box {i}: {v} m/s, {w} rad/s"
            );
            if i > 0 {
                let below = world.bodies[boxes[i - 1].0].translation().y;
                let into = 2.0 * column.half - (r.translation().y - below);
                assert!(
                    into < 0.002,
                    "gap {gap}, box {i}: {into} m into the one below"
                );
            }
        }
    }
}

/// Known failure, kept ignored: found by the property above (`PROPTEST_RNG_SEED=5129`; also
/// on stop 62's code). Two 10 g boxes of 4.3 cm dropped 48 cm apart with friction on
/// 2880 N/m: the upper one, falling at 3.4 m/s (5.7 cm a step, more than its size), ends step
/// 20 with its centre 1.0 cm over the lower box's (they overlap by three quarters of their
/// height: rapier steps this scene, with no CCD between two dynamic bodies and no step guard),
/// and at step 21 the lower box leaves at 11.4 m/s spinning at 1,500 rad/s: 4.2 J from the
/// column's 0.076 J. The same column on a fixed box for ground, stepped by rapier alone, ends
/// step 20 the same way and loses energy at step 21 (0.065 J to 0.0064 J): the surface's
/// coupling of the lower box (a dynamic tool) makes it. Traced at stop 64 (four substeps a
/// step): in step 21 rapier's step slows the upper box from 3.43 to about 1.8 m/s and pushes
/// the lower one down at about 2 m/s (their contact), and the surfaces replay both from the step's
/// start. The upper box, its bottom 1 cm over the plate and inside the lower box, is itself a
/// dynamic tool: its predicted motion crosses the plate, and in the first substep the plate
/// stops it (0.030 N·s) through the lower box, pressing the plate's vertices under both down;
/// the lower box's rows, those vertices moving away from it, take nothing, and it sinks 2 mm
/// into the plate. The push out then turns it 0.09 rad, and in the third substep the plate
/// throws it (0.13 N·s, 1,300 rad/s). The upper box, stopped by the plate, ends at +1.2 m/s:
/// rapier's push, replayed as a force over the substeps, kept acting after the plate had
/// stopped it. Tried and not kept: adding that push only until the body's velocity along it
/// reaches what rapier's step left it (the upper box then ended at -0.17 m/s, the lower was
/// thrown as before, and a stack of three frictionless boxes leant 16.8 mm, over its 15 mm
/// bound: `auto_tools::stacked_boxes_stand_on_the_plate_and_it_carries_them_all`); leaving
/// out a dynamic tool's speculative contacts whose gap (over rapier's 5 mm allowed error) lay
/// within another dynamic tool (the upper box's, its corners within 5 mm of the lower box)
/// made 1.44 J at the same step instead of 4.2 J (not traced further).
#[test]
#[ignore = "known failure: a box falling into the one below in one step throws it"]
fn a_box_falling_into_the_one_below_does_not_throw_it() {
    let column = Column::drawn(
        2,
        (-1.669_729_7, -1.994_363_5, 3.459_063),
        0.475_245_03,
        true,
    );
    column.drop(600).unwrap();
}
