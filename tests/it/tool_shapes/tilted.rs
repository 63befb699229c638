//! The U and the two jaws turned any way and tilted, pressed anywhere near the plate's centre
//! (a property test and the cases it found), and the contacts a tilted face, edge or corner
//! makes beside a vertex the tool holds: each checked as the module's straight presses are
//! (the pins' balance, no vertex inside, no corner under the surface, a dent under the tool).

use super::*;

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    /// The U or the jaws, turned any way about the vertical and tilted up to 0.4 rad about a
    /// horizontal axis, pressed anywhere within 15 cm of the plate's centre: the pins' balance,
    /// no vertex inside, no corner under the surface, a dent under the lowest corner.
    #[test]
    fn tilted_non_convex_and_compound_tools_hold_anywhere(
        u in any::<bool>(), yaw in 0.0f32..std::f32::consts::TAU, tilt in 0.0f32..0.4,
        tilt_axis in 0.0f32..std::f32::consts::TAU, x in -0.15f32..0.15, z in -0.15f32..0.15,
    ) {
        tilted_tool_holds(u, (yaw, tilt, tilt_axis), (x, z));
    }
}

/// The U (`u`) or the jaws, turned by `yaw` about the vertical and tilted by `tilt` about a
/// horizontal axis `tilt_axis` from x, pressed over `(x, z)`: the property test's checks.
fn tilted_tool_holds(u: bool, (yaw, tilt, tilt_axis): (f32, f32, f32), (x, z): (f32, f32)) {
    let turn = turned(yaw, tilt, tilt_axis);
    let (shape, probes) = if u { (u_shape(), u_corners()) } else { jaws() };
    let lowest = probes
        .iter()
        .map(|c| (turn * *c).y)
        .fold(f32::MAX, f32::min);
    let r = press_at(shape, turn, lowest, &probes, (x, z));
    let tip = probes
        .iter()
        .copied()
        .min_by(|a, b| (turn * *a).y.total_cmp(&(turn * *b).y))
        .unwrap();
    let at = r.world.colliders[r.tool].position().transform_point(tip);
    if u {
        check(&r, inside_u(&r), &[(at.x, at.z)], "U");
    } else {
        check(&r, inside_of(&r), &[(at.x, at.z)], "jaws");
    }
}

/// The U legs down, turned 1.44 rad and tilted 0.174 rad (10 degrees), pressed 0.11 m from the
/// plate's centre (`PROPTEST_RNG_SEED=5103` of the property test above, at 64 cases).
fn u_tilted_ten_degrees() -> Pressed {
    let turn = turned(1.440_278_9, 0.174_212_35, 5.964_453);
    let probes = u_corners();
    let lowest = probes
        .iter()
        .map(|c| (turn * *c).y)
        .fold(f32::MAX, f32::min);
    press_at(
        u_shape(),
        turn,
        lowest,
        &probes,
        (-0.047_794_826, 0.102_089_81),
    )
}

/// At rest the U tilted 10 degrees reads the force the pins hold (within 5 %). Its leg's face
/// holds a surface vertex on a sliding hold, and the tool's edges press points of the triangles
/// round it, their normals about 10 degrees off the face's: the solve moved that vertex with
/// the points' rows, and the hold took only the part along its normal. The tool's force, which
/// reads a held vertex's springs along its hold's normal and leaves a held vertex's share out
/// of the points' impulses, lost the rest: it read (0.41, 6.39, 0.04) N for the pins' (0.45,
/// 6.51, -0.50) N, 8.7 % of the press off. Now the points also report what their rows gave
/// held vertices across their holds' normals (`MassSpringSurface::point_held_across`).
#[test]
fn a_u_tilted_ten_degrees_reads_the_pins_force() {
    balances_the_pins(&u_tilted_ten_degrees(), 0.05, "U tilted 10 degrees");
}

/// The same U ([`u_tilted_ten_degrees`]) at rest: its free vertices 6-9 cm from it are at rest
/// with the springs. Kept ignored from stop 60 to stop 64: vertex 192, 89 mm from the tool,
/// held still under a 0.10 N spring force (the check allows 1.6 % of that). A point of the
/// leg's edge has 96 % of its weight on the vertex the leg's face holds: each substep its
/// press moved the free vertex of its edge by its depth over that weight, through the
/// filter's columns as far as vertex 192, and the step's springs pulled them back: a cycle at
/// rest, not an equilibrium. Passes since presses with under 2 % of their weight on free
/// vertices, the rest on vertices sliding holds keep on the U's faces, slide those along the
/// faces (`MassSpringSurface::press_points`): here presses with 0.03-0.4 % of their weight on
/// free vertices, which were left to the held vertices before. How that settles the cycle
/// was not traced.
#[test]
fn a_u_tilted_ten_degrees_balances_the_pins() {
    tilted_tool_holds(
        true,
        (1.440_278_9, 0.174_212_35, 5.964_453),
        (-0.047_794_826, 0.102_089_81),
    );
}

/// A case the property test above found at 64 cases with `PROPTEST_RNG_SEED=5101` (kept
/// ignored from stop 60 to stop 64). The U legs down, turned 1.88 rad and tilted 0.027 rad,
/// pressed 0.18 m from the 1 m plate's centre: from step 33 a leg's corner was under the
/// deformed surface, 26 um and then up to 0.11 mm while the U pressed on (the check allows
/// 10 um; the cells are 62.5 mm). The corner lies 1.3 mm from a surface vertex that the leg's
/// bottom face holds: its presses have 99 % of their weight on that held vertex, less than
/// the 2 % on free vertices below which `MassSpringSurface::press_points` left a point to its
/// held vertices (pressing it would move the free ones by its depth over that weight), and
/// the held vertex stayed on the face, which the tilt puts above the corner. Such a press now
/// also slides the held vertex along the face (its hold is a sliding one), and the corner
/// stays out.
#[test]
fn a_tilted_u_keeps_its_corners_out() {
    tilted_tool_holds(
        true,
        (1.883_303_6, 0.027_200_622, 2.338_692),
        (0.123_035_5, -0.134_426_19),
    );
}

#[test]
fn two_jaw_compound_tool_holds_with_both_jaws_and_gets_the_pins_force() {
    let (shape, probes) = jaws();
    let r = press(shape, Rotation::IDENTITY, 0.0, &probes);
    check(
        &r,
        inside_of(&r),
        &[(-0.062, -0.021), (0.088, -0.021)],
        "two jaws",
    );
}

/// A case the property test above found with `PROPTEST_RNG_SEED=3` (shrunk to the two jaws
/// over the plate's centre, untilted): one jaw alone, a 3 × 6 × 4 cm cuboid pressed flat at
/// (-0.075, 0), had its corner (-0.09, -0.02) 1.1 mm under the surface at step 25. Its face
/// holds the surface vertex at (-0.0625, 0); the corner lies in a triangle with that vertex,
/// whose press `MassSpringSurface::press_points` left to the vertex's holder, and the
/// triangle's two free vertices stayed up. It now presses them.
#[test]
fn a_flat_cuboid_keeps_its_corners_out_of_a_triangle_beside_a_held_vertex() {
    let shape = SharedShape::cuboid(0.015, 0.03, 0.02);
    let probes: Vec<Vector> = [-0.015, 0.015]
        .iter()
        .flat_map(|&x| [Vector::new(x, -0.03, -0.02), Vector::new(x, -0.03, 0.02)])
        .collect();
    press_at(shape, Rotation::IDENTITY, -0.03, &probes, (-0.075, 0.0));
}

/// The U legs down, tilted 0.014 rad about a horizontal axis 1.81 rad from x (the property
/// test's random cases below), pressed in over `at`: the plate at rest at the end.
fn tilted_u_at_rest(at: (f32, f32)) -> Pressed {
    let axis = Vector::new(1.8131207f32.cos(), 0.0, 1.8131207f32.sin());
    let turn = Rotation::from_axis_angle(axis, 0.014028846);
    let r = u_pressed(turn, at);
    let s = &r.set.get(r.surface).unwrap().surface;
    let fastest = (0..s.num_vertices() as u32)
        .map(|i| s.velocity(i).length())
        .fold(0.0, f32::max);
    assert!(fastest < 1e-3, "a vertex still moves at {fastest} m/s");
    r
}

/// A case the property test above found on a random seed: the U legs down, tilted 0.014 rad
/// about a horizontal axis 1.81 rad from x, over (0, 0.0895). A vertex held on a leg's wall
/// slid down at 0.25 m/s and was put back on the leg by position alone at every substep,
/// while a neighbour see-sawed up at the same speed through a point press both load: the plate
/// never moved, and the dampers of that motion took 1 N of a 10.5 N press off the tool's
/// reaction (9.54 N against the pins' 10.51 N). A held vertex put back along another direction
/// than the normal now loses its motion into the tool along that move: the plate comes to rest
/// and the two forces balance.
#[test]
fn a_vertex_held_on_a_legs_wall_comes_to_rest_and_the_forces_balance() {
    let r = tilted_u_at_rest((0.0, 0.08948548));
    balances_the_pins(&r, 0.01, "U on a wall-held vertex");
}

/// Another case of that property test (the same U and tilt, 5.5 mm aside): the U held one
/// vertex at the foot of a leg's wall, held along the wall's normal. Its springs pulled it down
/// and away below the leg's edge, which is no pull along that normal, so the hold never let it
/// go: the step carried it 0.3 mm down at every substep and the hold put it back up by position
/// (at 0.15 m/s), and the presses around it cycled with it. The vertex kept a pull on the tool
/// the reaction did not count: 10.05 N against the pins' 10.67 N, and a vertex 10 cm off the
/// tool held still with 0.14 N on it. A vertex found outside the tool is now let go when its
/// springs pull it along the way from the tool's nearest point to it.
#[test]
fn a_vertex_left_under_a_legs_edge_is_let_go_and_the_forces_balance() {
    let r = tilted_u_at_rest((-0.0054680738, 0.08948548));
    free_vertices_away_from_the_tool_balance(&r, "U over a vertex under a leg's edge");
    balances_the_pins(&r, 0.01, "U over a vertex under a leg's edge");
}

/// A case of the tilted-tools property test (a random seed): the jaws turned 1.61 rad about
/// the vertical over (0.11, 0), coming down flat. A jaw's face holds the surface vertex under
/// it and its corner lies in a triangle with 0.83 of its weight on that vertex; the press was
/// left to the vertex's holder (less than a quarter of its weight on free vertices) and the
/// corner went 66 µm under the triangle's free side at step 25. It is now pressed while the
/// way its free vertices must go is short.
#[test]
fn a_jaws_corner_beside_a_held_vertex_stays_out_of_its_triangle() {
    let r = jaws_pressed(Rotation::from_rotation_y(1.6115602), (0.110015064, 0.0));
    check(&r, inside_of(&r), &[], "jaws over (0.11, 0)");
}

/// Turned `yaw` about the vertical, then tilted `tilt` about the horizontal axis `tilt_axis`
/// from x (the tilted-tools property test's turn).
fn turned(yaw: f32, tilt: f32, tilt_axis: f32) -> Rotation {
    let horizontal = Vector::new(tilt_axis.cos(), 0.0, tilt_axis.sin());
    Rotation::from_axis_angle(horizontal, tilt) * Rotation::from_rotation_y(yaw)
}

/// The U legs down, turned by `turn`, pressed at `at` (`press_at` asserts after every step
/// that no leg's bottom corner is under the surface).
fn u_pressed(turn: Rotation, at: (f32, f32)) -> Pressed {
    let probes = u_corners();
    let lowest = probes
        .iter()
        .map(|c| (turn * *c).y)
        .fold(f32::MAX, f32::min);
    press_at(u_shape(), turn, lowest, &probes, at)
}

/// The jaws turned by `turn`, pressed at `at` (`press_at` asserts after every step that no
/// bottom corner is under the surface).
fn jaws_pressed(turn: Rotation, at: (f32, f32)) -> Pressed {
    let (shape, probes) = jaws();
    let lowest = probes
        .iter()
        .map(|c| (turn * *c).y)
        .fold(f32::MAX, f32::min);
    press_at(shape, turn, lowest, &probes, at)
}

/// A case of the tilted-tools property test (a random seed; it failed at the stop's starting
/// commit too): the jaws turned 1.37 rad about the vertical, tilted 0.039 rad about an axis
/// 0.33 rad from x, over (0.150, 0.148), both pressing between the surface's vertices. At
/// rest one jaw's contacts cycled with a period of four substeps: its corners on triangles
/// (146, 163, 164), (163, 180, 164) and (164, 180, 181) and its edge across (180, 164) pressed,
/// then some of them missing, then back, one corner 0.12 mm deep; the force at the end of each
/// substep read 10.15, 9.17, 10.04 and 8.84 N for the pins' 9.549 N (their mean right). The
/// cycle started from depths a few `f32` steps from zero whose sign flipped; such depths now
/// count as zero, and the force reads 9.584 N at every substep.
#[test]
fn a_jaws_contacts_between_vertices_hold_steady_at_rest_and_balance_the_pins() {
    let (yaw, tilt, tilt_axis) = (1.3718774f32, 0.038617287f32, 0.3322033f32);
    let turn = turned(yaw, tilt, tilt_axis);
    let r = jaws_pressed(turn, (0.14987464, 0.14828624));
    check(&r, inside_of(&r), &[], "jaws over (0.150, 0.148)");
    // Steady through the step: the last substep's force is the step's mean.
    let reaction = r.set.tool_reaction(r.tool).unwrap();
    assert!(steady(&reaction), "{reaction:?}");
}

/// A case of the tilted-tools property test (random seed 9003; it failed at the stop's
/// starting commit too): the jaws turned 1.0006 rad about the vertical, untilted, over
/// (-0.044, 0.095). A jaw's flat face rests on three triangles of the 62.5 mm plate and
/// presses them at seven or eight points (its corners, its edges across theirs) on five
/// vertices. At rest the face see-sawed, its force at the end of three steps 10.97, 10.07 and
/// 9.67 N for the pins' 10.39 N, its vertices moving at up to 13 cm/s: the constraint solve
/// left out rows that repeat others, and one it left out let its point rise 0.12 mm into the
/// jaw; and a press the others' pushes satisfied was held to move away from the jaw at the
/// speed those pushes gave it (up to 7.6 cm/s), throwing the triangle 0.19 mm under the face.
/// Now the force is the pins' (10.413 N) at every substep.
#[test]
fn a_jaws_face_on_a_few_triangles_rests_without_see_sawing() {
    let r = jaws_pressed(
        Rotation::from_rotation_y(1.0006113),
        (-0.044105347, 0.094921745),
    );
    jaws_rest_on_the_pins(&r, "jaws over (-0.044, 0.095)");
}

/// A case of the tilted-tools property test (random seed 9014; it failed at this stop's
/// starting commit): the jaws turned 4.51 rad about the vertical, tilted 0.0036 rad, over
/// (0.062, 0.125). One jaw held a plate vertex on its bottom edge; the held normal, the
/// nearest of two faces the vertex lay on, took the side face's at every other substep, so
/// the vertex slid down along it 0.27 mm a substep (its vertical motion counted as
/// tangential) and was put back at the next. The force at the step's last substep read
/// 6.71 N for the pins' 11.16 N (14 N and 6.7-7.6 N in turn from substep to substep). At an
/// edge the face the vertex's springs push against is now taken: the pins' force, at every
/// substep.
#[test]
fn a_vertex_on_a_jaws_edge_is_held_by_the_face_it_pushes() {
    let horizontal = Vector::X;
    let turn =
        Rotation::from_axis_angle(horizontal, 0.0036305208) * Rotation::from_rotation_y(4.5123277);
    let r = jaws_pressed(turn, (0.06173612, 0.12480898));
    jaws_rest_on_the_pins(&r, "jaws over (0.062, 0.125)");
}

/// A case of the tilted-tools property test (random seed 6102; it failed at this stop's
/// starting commit): the jaws turned 1.26 rad about the vertical, untilted, over (0.117,
/// 0.015). A jaw's bottom edge crosses the surface edge from a vertex the jaw holds to one
/// 6 cm outside it, 7.6 % of the way: the point, pressed after each substep, held the far
/// vertex down at the jaw's depth, but in the filtered step its row nearly repeated the held
/// vertex's and was left out, so the far vertex sprang 0.24 mm up in every substep and was
/// pushed back after it. Its five free neighbours never came to rest (0.07 N each, held by
/// nothing, at the end of every step). The held vertex's part of the row is now counted as
/// known (its hold fixes it), and the row holds the far vertex through the step.
#[test]
fn a_jaws_edge_beside_a_held_vertex_holds_the_far_vertex_through_the_step() {
    let r = jaws_pressed(
        Rotation::from_rotation_y(1.2642744),
        (0.11669069, 0.015132333),
    );
    jaws_rest_on_the_pins(&r, "jaws over (0.117, 0.015)");
}

/// A case of the tilted-tools property test (random seed 6105, rounded; it failed at this
/// stop's starting commit): the U turned 3.44 rad about the vertical, tilted 0.39 rad about an
/// axis 4.18 rad from x, over (0.036, 0). A plate vertex lay on a leg's bottom edge, and the
/// leg's corner pressed the triangle beside it with 0.78 of the point's weight on that vertex.
/// The vertex was held along the normal of the mesh's first triangle (an end cap's, whatever
/// the point), so the press's push moved it off the edge in every substep, the hold put it
/// back by position alone, and the press pushed the triangle's two free vertices down 0.14
/// and 0.07 mm after it: the tool's force read 4.63 N for the pins' 6.38 N. With the right
/// face (the leg's bottom, the one its springs push it against) the same cycle ran along that
/// face: 6.14 N. Now a vertex that slides off the face it was held on is let go: it rests
/// outside the leg, the corner's press holds its triangle, and the forces balance.
#[test]
fn a_vertex_pushed_off_a_legs_edge_by_a_corners_press_is_let_go() {
    let (yaw, tilt, tilt_axis) = (3.444578f32, 0.39f32, 4.183843f32);
    let r = u_pressed(turned(yaw, tilt, tilt_axis), (0.036, 0.0));
    check(&r, inside_u(&r), &[], "U over (0.036, 0)");
    balances_the_pins(&r, 0.01, "U over (0.036, 0)");
    let reaction = r.set.tool_reaction(r.tool).unwrap();
    assert!(steady(&reaction), "{reaction:?}");
}

/// The jaws' checks ([`check`]), their force within 1 % of the pins' and steady through the
/// step (the last substep's force the step's mean).
fn jaws_rest_on_the_pins(r: &Pressed, name: &str) {
    check(r, inside_of(r), &[], name);
    balances_the_pins(r, 0.01, name);
    let reaction = r.set.tool_reaction(r.tool).unwrap();
    assert!(steady(&reaction), "{reaction:?}");
}
