//! Whether rapier would solve contacts between two colliders: the guard corrects only such
//! pairs, so a body passes through whatever rapier lets it pass (sensors, excluded collision or
//! solver groups, disabled colliders and bodies, `ActiveCollisionTypes`, joints with contacts
//! disabled, the user's `filter_contact_pair`).
//!
//! rapier 0.36 decides this in its narrow phase (`geometry/narrow_phase/pair_update.rs`,
//! `process_pair`) with no public entry point, and a pair the step guard meets may not be in
//! the narrow phase at all (a body that tunneled past it within the step). The rules are
//! therefore applied here in rapier's own order, on rapier's own flags, and the user's
//! filtering hook is asked exactly as rapier asks it.

use crate::math::{Real, Vector};
use rapier3d::dynamics::{ImpulseJointSet, MultibodyJointSet, RigidBodySet, RigidBodyType};
use rapier3d::geometry::{
    ColliderHandle, ColliderSet, ContactManifold, ContactManifoldData, SolverFlags,
};
use rapier3d::pipeline::{
    ActiveHooks, ContactModificationContext, ModifiableContacts, ModifiableManifold,
    PairFilterContext, PhysicsHooks, PhysicsWorld,
};

/// `true` if rapier would compute and solve rigid contacts between `c1` and `c2` (the user's
/// `hooks` asked for pairs with `ActiveHooks::FILTER_CONTACT_PAIRS`). With `tool`, the
/// `ActiveCollisionTypes` rule is skipped: a tool is a kinematic body the crate stops at first
/// touch itself (its proxy), also against fixed colliders, which rapier's default collision
/// types leave out. Joints are rapier's rule too: bodies joined by an impulse or multibody
/// joint with contacts disabled, and links of a multibody whose self-contacts are off, are
/// never paired (a ragdoll's limbs overlap at their joints).
#[allow(clippy::too_many_arguments)]
pub(crate) fn rapier_solves_pair(
    bodies: &RigidBodySet,
    colliders: &ColliderSet,
    (impulse_joints, multibody_joints): (&ImpulseJointSet, &MultibodyJointSet),
    hooks: &dyn PhysicsHooks,
    c1: ColliderHandle,
    c2: ColliderHandle,
    tool: bool,
) -> bool {
    let (Some(co1), Some(co2)) = (colliders.get(c1), colliders.get(c2)) else {
        return false;
    };
    // Disabled colliders (a disabled body disables its colliders) are not in the broad phase;
    // sensors get intersections, never contacts.
    if !co1.is_enabled() || !co2.is_enabled() || co1.is_sensor() || co2.is_sensor() {
        return false;
    }
    let (rb1, rb2) = (co1.parent(), co2.parent());
    if rb1.is_some() && rb1 == rb2 {
        return false;
    }
    if let (Some(b1), Some(b2)) = (rb1, rb2) {
        if impulse_joints
            .joints_between(b1, b2)
            .any(|(_, j)| !j.data.contacts_enabled)
        {
            return false;
        }
        if let (Some(l1), Some(l2)) = (
            multibody_joints.rigid_body_link(b1),
            multibody_joints.rigid_body_link(b2),
        ) {
            if l1.multibody == l2.multibody {
                if multibody_joints
                    .get_multibody(l1.multibody)
                    .is_some_and(|mb| !mb.self_contacts_enabled())
                {
                    return false;
                }
                if multibody_joints
                    .joint_between(b1, b2)
                    .is_some_and(|(_, _, link)| !link.joint.data.contacts_enabled)
                {
                    return false;
                }
            }
        }
    }
    let body_type = |h: Option<_>| {
        h.and_then(|h| bodies.get(h))
            .map_or(RigidBodyType::Fixed, |b| b.body_type())
    };
    let (t1, t2) = (body_type(rb1), body_type(rb2));
    if !tool
        && !co1.active_collision_types().test(t1, t2)
        && !co2.active_collision_types().test(t1, t2)
    {
        return false;
    }
    if !co1.collision_groups().test(co2.collision_groups()) {
        return false;
    }
    let active = co1.active_hooks() | co2.active_hooks();
    let flags = if active.contains(ActiveHooks::FILTER_CONTACT_PAIRS) {
        let context = PairFilterContext {
            bodies,
            colliders,
            collider1: c1,
            collider2: c2,
            rigid_body1: rb1,
            rigid_body2: rb2,
        };
        match hooks.filter_contact_pair(&context) {
            Some(flags) => flags,
            None => return false,
        }
    } else {
        SolverFlags::default()
    };
    flags.contains(SolverFlags::COMPUTE_RIGID_IMPULSES)
        && co1.solver_groups().test(co2.solver_groups())
}

/// `true` if the user's `modify_solver_contacts` removes the contact the step guard is about to
/// correct: a one-way platform the body passes from below, or any rule of the user's own. rapier
/// calls that hook only for pairs with `ActiveHooks::MODIFY_SOLVER_CONTACTS`, on the contacts its
/// narrow phase found; the guard meets contacts rapier may never have seen (a body that went
/// through within the step), so the hook is asked on a manifold built from the first touch:
/// rapier's pair order `(c1, c2)`, the first-touch normal (`normal`, out of `partner`) as the
/// manifold normal, one solver contact at `point`, `depth` deep, and the `user_data` rapier's
/// manifold of the pair carries (the state a one-way platform keeps there). rapier's solver
/// contacts cannot be built outside rapier (a private field), so the contact is a copy of one
/// rapier made (the pair's, else any), rewritten, or a zeroed one when there is none.
#[allow(clippy::too_many_arguments)]
pub(crate) fn user_removes_contact(
    world: &PhysicsWorld,
    hooks: &dyn PhysicsHooks,
    (c1, c2): (ColliderHandle, ColliderHandle),
    partner: ColliderHandle,
    normal: Vector,
    point: Vector,
    depth: Real,
) -> bool {
    let (Some(co1), Some(co2)) = (world.colliders.get(c1), world.colliders.get(c2)) else {
        return false;
    };
    if !(co1.active_hooks() | co2.active_hooks()).contains(ActiveHooks::MODIFY_SOLVER_CONTACTS) {
        return false;
    }
    let pair = world.narrow_phase.contact_pair(c1, c2);
    let solver_contacts = |p: &rapier3d::geometry::ContactPair| {
        p.manifolds()
            .iter()
            .flat_map(|m| m.data.solver_contacts.iter().copied())
            .next()
    };
    let template = pair
        .and_then(solver_contacts)
        .or_else(|| world.narrow_phase.contact_pairs().find_map(solver_contacts));
    // SAFETY: a solver contact is plain data (`f32`s, glam vectors of `f32`, `u32`s:
    // `#[repr(C)]`, no references, no invariants), for which all-zero bytes are a valid value.
    // rapier offers no constructor (its `padding` field is private), and a world whose narrow
    // phase holds no solver contact yet has no copy to take.
    let mut contact = template
        .unwrap_or_else(|| unsafe { std::mem::zeroed::<rapier3d::geometry::SolverContact>() });
    // The manifold normal points out of collider 1.
    let n1 = if partner == c1 { normal } else { -normal };
    contact.anchor1 = point;
    contact.anchor2 = point - n1 * depth;
    contact.dist = -depth;
    contact.tangent_velocity = Vector::ZERO;
    let mut manifold = ContactManifold::with_data(0, 0, ContactManifoldData::default());
    manifold.local_n1 = co1.position().rotation.inverse() * n1;
    manifold.local_n2 = co2.position().rotation.inverse() * -n1;
    let mut user_data = pair
        .and_then(|p| p.manifolds().first())
        .map_or(0, |m| m.data.user_data);
    let mut contacts = vec![contact];
    let (mut n, mut friction, mut restitution) = (n1, 0.0, 0.0);
    let mut context = ContactModificationContext {
        bodies: &world.bodies,
        colliders: &world.colliders,
        collider1: c1,
        collider2: c2,
        rigid_body1: co1.parent(),
        rigid_body2: co2.parent(),
        contacts: ModifiableContacts::Rigid(ModifiableManifold {
            manifold: &manifold,
            solver_contacts: &mut contacts,
            normal: &mut n,
            friction: &mut friction,
            restitution: &mut restitution,
            user_data: &mut user_data,
        }),
    };
    hooks.modify_solver_contacts(&mut context);
    contacts.iter().all(|c| c.dist >= 0.0)
}
