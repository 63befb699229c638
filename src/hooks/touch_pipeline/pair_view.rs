//! One pair as the step guard reads it ([`PairView`]), what it remembers of a pair between
//! steps ([`PairState`]), and the way out of an overlap ([`push_out`]).

use super::rapier_contacts::RapierContact;
use super::*;
use crate::geometry::ContactConfiguration;

/// The overlap of a pair when it was last measured, and both bodies' odometers then.
#[derive(Copy, Clone, Debug)]
pub(super) struct PairState {
    pub overlap: Real,
    pub odo_self: Real,
    pub odo_partner: Real,
}

/// One pair as the guard reads it, before deciding anything: the partner's pose now, its
/// translation over the step, the pair's relative travel (translation
/// plus both rotations' arcs), rapier's contact points of the pair and whether they are
/// trusted at that travel, and whether the partner is dynamic.
#[derive(Copy, Clone, Debug)]
pub(super) struct PairView {
    pub partner_pose: Pose,
    pub dp: Vector,
    pub travel: Real,
    pub rapier: Option<RapierContact>,
    pub trusted: bool,
    pub partner_dynamic: bool,
}

impl PairView {
    /// A slow pair the guard has nothing to do for, decided from rapier's points alone (the
    /// same rules the guard applies to every pair it looks at): a resting pair with a dynamic
    /// partner or within the resting slop, a non-resting one no deeper than the slop, or, with
    /// no points, one that travelled less than the slop.
    pub fn calm(&self, options: &TouchOptions) -> bool {
        let slop = options.penetration_slop;
        match &self.rapier {
            Some(r) if r.in_contact_at_start => {
                self.partner_dynamic || (self.trusted && r.depth <= options.resting_slop)
            }
            Some(r) => !options.report_touching && self.trusted && r.depth <= slop,
            None => !options.report_touching && self.travel <= slop,
        }
    }
}

/// The relative motion over one step under which two bodies cannot have passed through each
/// other: the smaller of their touch meshes' thinnest extents (a flat partner, of zero extent,
/// counts as the mover's).
pub(super) fn safe_step(mesh: &TouchMesh, partner_mesh: &TouchMesh) -> Real {
    match (mesh.min_extent(), partner_mesh.min_extent()) {
        (a, b) if b > 0.0 => a.min(b),
        (a, _) => a,
    }
}

/// How deep `mover` (at `pose`) overlaps `partner` (at `partner_pose`) by parry's contact
/// query with a prediction of 0: 0 for shapes apart (parry answers `None`), minus the
/// distance of the contact it answers (negative for a positive distance, one of its wrong
/// answers: seen for a small tumbling cuboid on a large one, +1.1 mm where a corner was
/// 1.1 mm deep), `None` when parry has no query for the shapes.
pub(super) fn parry_depth(
    (partner, partner_pose): (&rapier3d::geometry::Collider, &Pose),
    (mover, pose): (&rapier3d::geometry::Collider, &Pose),
) -> Option<Real> {
    parry3d::query::contact(partner_pose, partner.shape(), pose, mover.shape(), 0.0)
        .ok()
        .map(|c| c.map_or(0.0, |c| -c.dist))
}

/// The way out of an overlap along `out` (a world direction out of the partner) for the mover
/// at its pose now: on the shapes themselves when the pair is `curved`
/// ([`Reconstructor::push_out_shapes`]), by the exact method on the touch meshes otherwise
/// (and when parry has no distance query for the shapes).
pub(super) fn push_out(
    options: ReconstructionOptions,
    curved: bool,
    (partner, partner_mesh, partner_pose): (&rapier3d::geometry::Collider, &TouchMesh, &Pose),
    (mover, mesh, pose): (&rapier3d::geometry::Collider, &TouchMesh, &Pose),
    out: Vector,
) -> Option<ContactConfiguration> {
    let mut rec = Reconstructor::new(ReconstructionOptions {
        zero_motion_direction: Some(-out),
        ..options
    });
    if curved {
        match rec.push_out_shapes(partner.shape(), partner_pose, mover.shape(), pose, out) {
            Ok(Some(c)) => return Some(c),
            Ok(None) => {}
            Err(_) => return None,
        }
    }
    rec.reconstruct(partner_mesh, partner_pose, mesh, pose, pose)
        .ok()
}
