//! The boxes the event search prunes triangle pairs with: a moving BVH node's box in the fixed
//! frame walked back along the ray ([`BoxTransform`]), the range of walks over which the two
//! meshes' boxes overlap, and the path of small moving meshes.
//!
//! Small moving meshes (a box, a wedge: [`SMALL_MOVER_TRIANGLES`] triangles or fewer) against
//! a fixed mesh: the moving triangles are put in the fixed frame once per pose and their own
//! boxes, loosened, are tried against the fixed BVH's leaves under the boxes' joint sweep,
//! instead of the two BVHs' joint descent. That descent turns a moving node's box into the
//! fixed frame for every node pair it visits (200-300 for a cube near the TriMesh stress
//! scene's 800-triangle floor); the triangles' exact boxes let through the same triangle pairs
//! or fewer (a node's box turned into the fixed frame contains its triangles'). Kept because a
//! bench shows it wins: a cube's penetration test against that floor 6.8 -> 3.9 us (the
//! bisection of its rotating path 55 -> 28 us a reconstruction), the scene's touch step
//! 1.49-1.52x -> 1.46-1.47x vanilla rapier and the CCD scene's 3.61-3.72x -> 3.53-3.64x
//! (`stress_scenes`, alternated binaries).

use super::events::{fixed_tri, moving_pt};
use super::primitives::triangles_cross;
use super::workspace::Workspace;
use super::*;

/// The most triangles a moving mesh has to be tested triangle by triangle.
pub(super) const SMALL_MOVER_TRIANGLES: usize = 32;

/// Whether `moving` is tested triangle by triangle at a pose.
pub(super) fn is_small_mesh(moving: &TouchMesh) -> bool {
    moving.num_triangles() <= SMALL_MOVER_TRIANGLES
}

/// Whether `moving` is tested triangle by triangle over walks `s` in `[s_min, s_max]` (both
/// finite: its sweep is a box).
pub(super) fn is_small(moving: &TouchMesh, s_min: f64, s_max: f64) -> bool {
    is_small_mesh(moving) && s_min.is_finite() && s_max.is_finite()
}

/// The boxes of `moving`'s triangles at frame `fr` (fixed frame), as centre and half extents
/// loosened by `pad`, into `out`; returns their joint box swept over the walks `s` in
/// `[s_min, s_max]` (the mesh moved by `-s u`).
pub(super) fn triangle_boxes(
    ws: &mut Workspace,
    moving: &TouchMesh,
    fr: &Frame,
    pad: Real,
    (s_min, s_max): (f64, f64),
    out: &mut Vec<(Vector, Vector)>,
) -> Aabb {
    out.clear();
    let (a, b) = ((-s_min * fr.u).as_vec3(), (-s_max * fr.u).as_vec3());
    let mut swept = Aabb::new_invalid();
    for idx in moving.indices() {
        let p = idx.map(|v| moving_pt(ws, moving, fr, v).as_vec3());
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        let (c, h) = ((lo + hi) * 0.5, (hi - lo) * 0.5 + Vector::splat(pad));
        swept.merge(&Aabb::new(c - h + a.min(b), c + h + a.max(b)));
        out.push((c, h));
    }
    swept
}

impl Reconstructor {
    /// Whether a surface triangle of the small mesh `moving` (shifted by `shift`, fixed
    /// frame) crosses one of `fixed`'s. Its triangles are put in the fixed frame once, one
    /// query of the fixed BVH with their joint box gives the fixed candidates, and each
    /// candidate is tried against the moving triangles whose own (exact, loosened by
    /// `margin`) boxes it meets: the same pairs the two BVHs' joint descent lets through or
    /// fewer (a moving node's box turned into the fixed frame contains its triangles'), for
    /// a quarter of the node tests. (A cube turning against an 800-triangle TriMesh floor:
    /// 200-300 node boxes turned and tested for each pose apart, 8-10 us a test.)
    pub(super) fn small_mover_crosses(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        shift: DVec3,
        margin: Real,
    ) -> bool {
        let mut tris = std::mem::take(&mut self.ws.m_tris);
        tris.clear();
        let mut all = Aabb::new_invalid();
        for idx in moving.indices() {
            let b = idx.map(|v| moving_pt(&mut self.ws, moving, fr, v) + shift);
            let (lo, hi) = (b[0].min(b[1]).min(b[2]), b[0].max(b[1]).max(b[2]));
            let bx = Aabb::new(lo.as_vec3(), hi.as_vec3()).loosened(margin);
            all.merge(&bx);
            tris.push((b, bx));
        }
        let fbvh = fixed.bvh();
        let crosses = fbvh.intersect_aabb(&all).any(|tf| {
            let Some(nf) = fbvh.leaf_node(tf) else {
                return false;
            };
            let a = fixed_tri(fixed, tf);
            tris.iter().enumerate().any(|(tm, (b, bx))| {
                bx.intersects(&nf.aabb())
                    && triangles_cross(
                        (&a, fixed.flat_sides(tf)),
                        (b, moving.flat_sides(tm as u32)),
                        fr.tol,
                    )
            })
        });
        self.ws.m_tris = tris;
        crosses
    }
}

/// Moves boxes of the moving tree into the fixed frame and intersects them with boxes of the
/// fixed tree along the ray, with the rotation matrices and `1/u` computed once per query.
pub(super) struct BoxTransform {
    rot: glamx::Mat3,
    abs_rot: glamx::Mat3,
    tra: Vector,
    inv_u: Vector,
    u: Vector,
    margin: Real,
}

impl BoxTransform {
    pub(super) fn new(pos12: &Pose, u: Vector, margin: Real) -> Self {
        let rot = glamx::Mat3::from_quat(pos12.rotation);
        let abs_rot = glamx::Mat3::from_cols(rot.x_axis.abs(), rot.y_axis.abs(), rot.z_axis.abs());
        Self {
            rot,
            abs_rot,
            tra: pos12.translation,
            inv_u: u.recip(),
            u,
            margin,
        }
    }

    /// The interval of `s` over which moving box `nm`, walked back by `s` along `-u`, overlaps
    /// fixed box `nf` (both loosened by the margin).
    #[inline]
    pub(super) fn overlap_interval(&self, nm: &BvhNode, nf: &BvhNode) -> Option<(Real, Real)> {
        let (mmin, mmax) = (nm.mins(), nm.maxs());
        let c = self.rot * ((mmin + mmax) * 0.5) + self.tra;
        let h = self.abs_rot * ((mmax - mmin) * 0.5) + Vector::splat(2.0 * self.margin);
        self.interval_of(c, h, nf)
    }

    /// [`BoxTransform::overlap_interval`] of a moving box already in the fixed frame: centre
    /// `c`, half extents `h` (loosened).
    #[inline]
    pub(super) fn interval_of(&self, c: Vector, h: Vector, nf: &BvhNode) -> Option<(Real, Real)> {
        let (fmin, fmax) = (nf.mins(), nf.maxs());
        // Need (c - h) - s u <= fmax and (c + h) - s u >= fmin, per axis.
        let a = (c - h - fmax) * self.inv_u;
        let b = (c + h - fmin) * self.inv_u;
        let (mut lo, mut hi) = (Real::NEG_INFINITY, Real::INFINITY);
        for k in 0..3 {
            if self.u[k].abs() < 1e-12 {
                if c[k] - h[k] > fmax[k] || c[k] + h[k] < fmin[k] {
                    return None;
                }
                continue;
            }
            let (l, r) = if self.u[k] > 0.0 {
                (a[k], b[k])
            } else {
                (b[k], a[k])
            };
            lo = lo.max(l);
            hi = hi.min(r);
        }
        (lo <= hi).then_some((lo, hi))
    }
}

/// The interval of `s` over which the moving mesh's box (walked back by `s`) overlaps the fixed
/// mesh's box.
pub(super) fn aabb_overlap_range(
    fixed: &TouchMesh,
    moving: &TouchMesh,
    fr: &Frame,
) -> Option<(f64, f64)> {
    let f = fixed.local_aabb();
    let pos12 = fr.pose12();
    let m = moving.local_aabb().transform_by(&pos12);
    let pad = fr.tol * 4.0 + 1e-5 * (f.extents().length() as f64).max(1e-12);
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        let (fmn, fmx) = (f.mins[k] as f64 - pad, f.maxs[k] as f64 + pad);
        let (mmn, mmx) = (m.mins[k] as f64, m.maxs[k] as f64);
        let uk = fr.u[k];
        // Need mmn - s uk <= fmx and mmx - s uk >= fmn.
        if uk.abs() < 1e-15 {
            if mmn > fmx || mmx < fmn {
                return None;
            }
            continue;
        }
        let a = (mmn - fmx) / uk;
        let b = (mmx - fmn) / uk;
        let (l, h) = if uk > 0.0 { (a, b) } else { (b, a) };
        lo = lo.max(l);
        hi = hi.min(h);
    }
    (lo <= hi).then_some((lo, hi))
}
