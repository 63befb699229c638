//! Where a surface vertex inside a rigid tool leaves it: the nearest point of the tool's
//! boundary, the exit along a direction (the vertex's inverse trajectory, eq. 1-2), and the
//! tool's outward normal there. Convex polyhedra use their face planes (parry's projection
//! and ray cast from inside a support map are iterative and approximate), balls, capsules,
//! cylinders and cones their exact normals, cylinders and cones their exact exits; other
//! shapes use parry's queries, cast at a size their tolerances suit.

use crate::math::{Pose, Real, Vector};
use parry3d::query::Ray;

/// The outward normal of `shape` at `local`, a point on its boundary (shape frame).
///
/// A convex polyhedron gives the normal of its nearest face plane; a ball, a capsule, a
/// cylinder or a cone, its exact normal ([`round_normal`]); a compound, its nearest part's normal; an
/// oriented triangle mesh, its nearest triangle's normal. Any other shape: a short ray
/// cast from just outside the point, back toward the shape's centre, hits the boundary next to
/// the point and returns the exact normal there (parry's feature normals at a boundary point
/// are unreliable for cylinders and cones, and missing for capsules and round shapes); where
/// parry's cast finds nothing (its tolerances are absolute: tools under about a centimetre),
/// the same cast on the shape scaled to a unit size. Fallbacks: the feature normal, then the
/// direction from the shape's centre.
pub(crate) fn outward_normal(
    shape: &dyn parry3d::shape::Shape,
    local: Vector,
    margin: Real,
) -> Vector {
    if let Some((n, _)) = shape
        .as_convex_polyhedron()
        .and_then(|poly| closest_face(poly, local))
    {
        return n;
    }
    if let Some(n) = round_normal(shape, local) {
        return n;
    }
    if let Some((inner, _)) = rounded(shape) {
        let q = project_inner(inner, local, true);
        if let Some(n) = (local - q.point).try_normalize().filter(|_| !q.is_inside) {
            return n;
        }
    }
    // A compound: the normal of the part whose boundary is nearest.
    if let Some(compound) = shape.as_compound() {
        if let Some((pose, part)) = nearest_part(compound, local) {
            let inner = outward_normal(part.as_ref(), pose.inverse_transform_point(local), margin);
            return pose.rotation * inner;
        }
    }
    // A triangle mesh (oriented: the tool's query shape): the normal of the nearest triangle
    // (the projection's sub-shape: parry answers for the triangle it is given; asked for the
    // first one, a U's end cap, it held a vertex on a leg's bottom edge along the cap's normal).
    if shape.as_trimesh().is_some() {
        let (proj, feature) = shape.project_local_point_and_get_feature(local);
        if let Some(n) = shape
            .feature_normal_at_point(proj.subshape, feature, proj.point)
            .filter(|n| n.is_finite())
            .and_then(|n| n.try_normalize())
        {
            return n;
        }
    }
    let aabb = shape.compute_local_aabb();
    let centre = aabb.center();
    let radial = (local - centre).try_normalize().unwrap_or(Vector::Y);
    let size = aabb.extents().max_element();
    let eps = 1e-3 * size + 10.0 * margin;
    let cast = |shape: &dyn parry3d::shape::Shape, scale: Real| {
        let ray = Ray::new((local + radial * eps) * scale, -radial);
        let hit = shape.cast_local_ray_and_get_normal(&ray, 2.0 * eps * scale, true)?;
        let n = hit.normal;
        (hit.time_of_impact > 0.0 && n.is_finite() && n.dot(radial) > 0.0)
            .then(|| n.try_normalize())
            .flatten()
    };
    if let Some(n) = cast(shape, 1.0) {
        return n;
    }
    // parry's ray cast on a support map works to absolute tolerances: on a tool under about a
    // centimetre it finds nothing (a cylinder of 0.3 mm radius, before its exact normals: no
    // hit, and the direction from the centre below, 34° off the bottom face's normal, dragged
    // the vertex it held backwards against friction). Again on the shape scaled to a unit size
    // (a uniform scale keeps the normals; support maps only: scaling a mesh copies it).
    if shape.as_support_map().is_some() {
        if let Some(n) =
            scaled(shape, size, 1.0).and_then(|(unit, scale)| cast(unit.as_ref(), scale))
        {
            return n;
        }
    }
    let (proj, feature) = shape.project_local_point_and_get_feature(local);
    shape
        .feature_normal_at_point(proj.subshape, feature, proj.point)
        .filter(|n| n.is_finite() && n.dot(radial) > 0.0)
        .unwrap_or(radial)
}

/// The part of `compound` whose boundary is nearest `local` (the compound's frame).
fn nearest_part(
    compound: &parry3d::shape::Compound,
    local: Vector,
) -> Option<&(Pose, parry3d::shape::SharedShape)> {
    compound.shapes().iter().min_by(|a, b| {
        let d = |(pose, part): &(Pose, parry3d::shape::SharedShape)| {
            (part.project_point(pose, local, false).point - local).length()
        };
        d(a).total_cmp(&d(b))
    })
}

/// [`outward_normal`] for a point on two or more flat faces at once ([`faces_at`]): the one
/// of those faces whose normal is most along `prefer` (shape frame; the way the point pushes
/// out of the tool). Elsewhere, and for `prefer` zero, [`outward_normal`].
///
/// At an edge the nearest face is a tie that rounding breaks: a plate vertex held on the
/// bottom edge of a resting jaw took the side face's normal at every other substep, slid
/// down along it (its vertical motion counted as tangential) by 0.27 mm a substep, was put
/// back at the next, and the jaw's force swung between 6.7 and 14 N for the pins' 11 N.
pub(crate) fn outward_normal_toward(
    shape: &dyn parry3d::shape::Shape,
    local: Vector,
    margin: Real,
    prefer: Vector,
) -> Vector {
    if prefer != Vector::ZERO && prefer.is_finite() {
        let on = faces_at(shape, local, margin);
        if on.len() > 1 {
            if let Some(n) = on
                .into_iter()
                .max_by(|a, b| a.dot(prefer).total_cmp(&b.dot(prefer)))
            {
                return n;
            }
        }
    }
    outward_normal(shape, local, margin)
}

/// The normals of the flat faces `local` (shape frame, on the boundary) lies on, when it lies
/// on two or more at once (an edge or a corner of a cuboid, a convex polyhedron or a triangle
/// mesh, or of a compound's nearest such part: face planes, or a mesh's triangles, within
/// `margin` of the nearest); one or none elsewhere (a face, a curved boundary).
pub(crate) fn faces_at(
    shape: &dyn parry3d::shape::Shape,
    local: Vector,
    margin: Real,
) -> Vec<Vector> {
    if let Some(compound) = shape.as_compound() {
        if let Some((pose, part)) = nearest_part(compound, local) {
            return faces_at(part.as_ref(), pose.inverse_transform_point(local), margin)
                .into_iter()
                .map(|n| pose.rotation * n)
                .collect();
        }
    }
    let tol = margin.max(1e-6 * shape.compute_local_aabb().extents().max_element());
    if let Some(mesh) = shape.as_trimesh() {
        return mesh_faces_at(mesh, local, tol);
    }
    let planes: Vec<(Vector, Real)> = if let Some(c) = shape.as_cuboid() {
        let h = c.half_extents;
        [Vector::X, Vector::Y, Vector::Z]
            .into_iter()
            .zip([h.x, h.y, h.z])
            .flat_map(|(axis, half)| [(axis, half), (-axis, half)])
            .map(|(n, half)| (n, n.dot(local) - half))
            .collect()
    } else if let Some(poly) = shape.as_convex_polyhedron() {
        face_planes(poly)
            .map(|(n, v)| (n, n.dot(local - v)))
            .collect()
    } else {
        Vec::new()
    };
    let nearest = planes
        .iter()
        .map(|p| p.1)
        .fold(Real::NEG_INFINITY, Real::max);
    planes
        .iter()
        .filter(|p| p.1 >= nearest - tol)
        .map(|p| p.0)
        .collect()
}

/// The distinct normals of the triangles of `mesh` (as wound: an oriented tool mesh's outward
/// normals) within `tol` of the nearest one to `local`: one at a face, two or more at an edge
/// or a corner. (Without it a point on a mesh's edge took the normal of whichever of the two
/// faces' triangles rounding made nearest, as a cuboid's did before [`outward_normal_toward`].)
fn mesh_faces_at(mesh: &parry3d::shape::TriMesh, local: Vector, tol: Real) -> Vec<Vector> {
    let probe = parry3d::bounding_volume::Aabb::new(
        local - Vector::splat(2.0 * tol),
        local + Vector::splat(2.0 * tol),
    );
    let faces: Vec<(Vector, Real)> = mesh
        .bvh()
        .intersect_aabb(&probe)
        .filter_map(|t| {
            let tri = mesh.triangle(t);
            let n = tri.normal()?;
            let d = (parry3d::query::PointQuery::project_local_point(&tri, local, false).point
                - local)
                .length();
            Some((n, d))
        })
        .collect();
    let nearest = faces.iter().map(|f| f.1).fold(Real::INFINITY, Real::min);
    let mut on: Vec<Vector> = Vec::new();
    for (n, d) in faces {
        // (Two triangles of one flat face give one normal.)
        if d <= nearest + tol && on.iter().all(|m| m.dot(n) < 1.0 - 1e-6) {
            on.push(n);
        }
    }
    on
}

/// The outward normal of a ball, a capsule, a cylinder or a cone at `local`, exactly (for the
/// last two, of the nearest of its flat face(s) and its side). parry's ray cast returns these
/// normals off by up to 3e-4 rad on a ball, 3e-3 on a capsule, 2e-5 on a cylinder's cap and
/// 2e-3 on its side, at random: a flat cylinder sliding over a plate wandered its vertex
/// sideways by more than its step and turned the kinetic friction (a 1.6 mm tool: the
/// tangential force swung between 0.6 and 1.0 of μd's).
fn round_normal(shape: &dyn parry3d::shape::Shape, local: Vector) -> Option<Vector> {
    if shape.as_ball().is_some() {
        return local.try_normalize();
    }
    if let Some(c) = shape.as_capsule() {
        let (a, b) = (c.segment.a, c.segment.b);
        let ab = b - a;
        let t = if ab.length_squared() > 0.0 {
            ((local - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        return (local - (a + ab * t)).try_normalize();
    }
    let rho = (local.x * local.x + local.z * local.z).sqrt();
    let radial = if rho > 0.0 {
        Vector::new(local.x / rho, 0.0, local.z / rho)
    } else {
        Vector::X
    };
    if let Some(c) = shape.as_cylinder() {
        let (h, r) = (c.half_height, c.radius);
        let (top, bottom, side) = ((h - local.y).abs(), (local.y + h).abs(), (r - rho).abs());
        return Some(if side <= top.min(bottom) {
            radial
        } else if top < bottom {
            Vector::Y
        } else {
            -Vector::Y
        });
    }
    if let Some(c) = shape.as_cone() {
        // Apex at +h, base of radius r at -h; the side's outward normal in the (ρ, y) plane.
        let (h, r) = (c.half_height, c.radius);
        let len = (4.0 * h * h + r * r).sqrt();
        let (nr, ny) = (2.0 * h / len, r / len);
        let side = (nr * (rho - r) + ny * (local.y + h)).abs();
        let base = (local.y + h).abs();
        return Some(if side <= base {
            (radial * nr + Vector::Y * ny).normalize()
        } else {
            -Vector::Y
        });
    }
    None
}

/// A rounded shape's inner shape and border radius: its boundary lies that far outside the
/// inner shape, so its normals, nearest points and distances follow from the inner shape's
/// exact queries. parry answers them on the rounded shape as a support map (iterative): a
/// rounded cylinder held still in a plate read forces swinging by 28 % from step to step.
pub(crate) fn rounded(
    shape: &dyn parry3d::shape::Shape,
) -> Option<(&dyn parry3d::shape::Shape, Real)> {
    if let Some(r) = shape.as_round_cuboid() {
        return Some((&r.inner_shape, r.border_radius));
    }
    if let Some(r) = shape.as_round_cylinder() {
        return Some((&r.inner_shape, r.border_radius));
    }
    if let Some(r) = shape.as_round_cone() {
        return Some((&r.inner_shape, r.border_radius));
    }
    if let Some(r) = shape.as_round_convex_polyhedron() {
        return Some((&r.inner_shape, r.border_radius));
    }
    if let Some(r) = shape.as_round_triangle() {
        return Some((&r.inner_shape, r.border_radius));
    }
    None
}

/// parry's projection of `local` on a rounded shape's inner shape; a convex polyhedron's is
/// GJK's, whose tolerances are absolute, so it is made at a fifth of a unit (a rounded hull of
/// 2 mm held in a plate read forces swinging by 45 % with its projection at its own size).
fn project_inner(
    inner: &dyn parry3d::shape::Shape,
    local: Vector,
    solid: bool,
) -> parry3d::query::PointProjection {
    if inner.as_convex_polyhedron().is_some() {
        let size = inner.compute_local_aabb().extents().max_element();
        if let Some((unit, scale)) = scaled(inner, size, 0.2) {
            let mut p = unit.project_local_point(local * scale, solid);
            p.point /= scale;
            return p;
        }
    }
    inner.project_local_point(local, solid)
}

/// `shape` (`size` its largest extent) scaled uniformly to a largest extent of `target`, a
/// size parry's absolute tolerances suit, and the scale; `None` for no finite size or a shape
/// parry cannot scale. A uniform scale keeps normals; lengths scale back by dividing.
fn scaled(
    shape: &dyn parry3d::shape::Shape,
    size: Real,
    target: Real,
) -> Option<(Box<dyn parry3d::shape::Shape>, Real)> {
    let scale = (size.is_finite() && size > 0.0).then(|| target / size)?;
    shape
        .scale_dyn(Vector::splat(scale), 24)
        .map(|unit| (unit, scale))
}

/// How far along the unit `d` the ray from `local` (inside, shape frame) leaves a cylinder or
/// a cone, exactly: the nearest of its flat face(s) and its side. parry's cast from inside
/// these support maps is off by up to 4 % of the size (a cylinder of 0.2 m, through its
/// side).
fn round_exit(shape: &dyn parry3d::shape::Shape, o: Vector, d: Vector) -> Option<Real> {
    // The smallest root at or past zero of `a t² + b t + c` that `keep` accepts.
    let first_root = |a: Real, b: Real, c: Real, keep: &dyn Fn(Real) -> bool| {
        let roots = if a.abs() > Real::EPSILON * (b.abs() + c.abs()).max(Real::MIN_POSITIVE) {
            let disc = b * b - 4.0 * a * c;
            if disc < 0.0 {
                return None;
            }
            let s = disc.sqrt();
            // The stable pair of roots.
            let q = -0.5 * (b + b.signum() * s);
            [q / a, if q != 0.0 { c / q } else { Real::INFINITY }]
        } else if b != 0.0 {
            [-c / b, Real::INFINITY]
        } else {
            return None;
        };
        roots
            .into_iter()
            .filter(|t| t.is_finite() && *t >= 0.0 && keep(*t))
            .min_by(|x, y| x.total_cmp(y))
    };
    let planes = |top: Option<Real>, bottom: Real| {
        let mut t = Real::INFINITY;
        if d.y > 0.0 {
            if let Some(top) = top {
                t = t.min((top - o.y) / d.y);
            }
        } else if d.y < 0.0 {
            t = t.min((bottom - o.y) / d.y);
        }
        t
    };
    let t = if let Some(c) = shape.as_cylinder() {
        let (h, r) = (c.half_height, c.radius);
        let side = first_root(
            d.x * d.x + d.z * d.z,
            2.0 * (o.x * d.x + o.z * d.z),
            o.x * o.x + o.z * o.z - r * r,
            &|_| true,
        );
        planes(Some(h), -h).min(side.unwrap_or(Real::INFINITY))
    } else if let Some(c) = shape.as_cone() {
        // Apex at +h, base of radius r at -h: the side is x² + z² = k² (h - y)².
        let (h, r) = (c.half_height, c.radius);
        let k2 = (r / (2.0 * h)).powi(2);
        let side = first_root(
            d.x * d.x + d.z * d.z - k2 * d.y * d.y,
            2.0 * (o.x * d.x + o.z * d.z + k2 * (h - o.y) * d.y),
            o.x * o.x + o.z * o.z - k2 * (h - o.y) * (h - o.y),
            &|t| o.y + t * d.y <= h,
        );
        planes(None, -h).min(side.unwrap_or(Real::INFINITY))
    } else {
        return None;
    };
    (t.is_finite()).then_some(t.max(0.0))
}

/// The face of `poly` whose plane is nearest above or least below `local`: its outward normal
/// and the signed distance of `local` to its plane. For a point inside the polyhedron that
/// face holds the nearest boundary point.
fn closest_face(poly: &parry3d::shape::ConvexPolyhedron, local: Vector) -> Option<(Vector, Real)> {
    face_planes(poly)
        .map(|(n, v)| (n, n.dot(local - v)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// Each face of `poly` as its outward normal and one of its vertices (shape frame).
fn face_planes(
    poly: &parry3d::shape::ConvexPolyhedron,
) -> impl Iterator<Item = (Vector, Vector)> + '_ {
    let (points, adj) = (poly.points(), poly.vertices_adj_to_face());
    poly.faces().iter().filter_map(move |f| {
        let v = points.get(*adj.get(f.first_vertex_or_edge as usize)? as usize)?;
        Some((f.normal, *v))
    })
}

/// How far `p` (world) is outside the tool (zero inside). For a convex polyhedron, at least
/// the farthest face plane's distance: parry's GJK calls a point inside when it is within an
/// absolute `10 f32::EPSILON` (about 1.2e-6) of the shape, more than the contact tolerance of
/// a tool under a few centimetres (`tests/it/grazing_drag.rs`: a 7.6 mm box given as its
/// convex hull, dragged over a plate it rested in, met 3.3 times its resting press with
/// GJK's answer, at most 1.7 times with the planes'; the same box as a cuboid, 1.3-1.4).
pub(crate) fn distance_outside(shape: &dyn parry3d::shape::Shape, pose: &Pose, p: Vector) -> Real {
    if let Some((inner, border)) = rounded(shape) {
        let local = pose.inverse_transform_point(p);
        let q = project_inner(inner, local, true);
        return if q.is_inside {
            0.0
        } else {
            ((local - q.point).length() - border).max(0.0)
        };
    }
    // A triangle mesh's projection of a point inside (an oriented mesh's) is the nearest
    // boundary point, not the point itself, and parry's solid distance is the distance to it:
    // a surface vertex 1.3 mm inside a U's leg read 1.3 mm outside. The projection says
    // whether the point is inside.
    if shape.as_trimesh().is_some() {
        let proj = shape.project_point(pose, p, true);
        return if proj.is_inside {
            0.0
        } else {
            (proj.point - p).length()
        };
    }
    let gjk = shape.distance_to_point(pose, p, true);
    match shape.as_convex_polyhedron() {
        Some(poly) => {
            let plane = closest_face(poly, pose.inverse_transform_point(p)).map_or(0.0, |f| f.1);
            gjk.max(plane)
        }
        None => gjk,
    }
}

/// The nearest point of the tool's boundary to `p` (world). parry's projection of a point
/// inside a convex polyhedron is approximate, so there the nearest face plane is used.
pub(crate) fn nearest_on_boundary(
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    p: Vector,
) -> Vector {
    boundary_point(shape, pose, p).0
}

/// The nearest point of the tool's boundary to `p` (world), and whether `p` is inside the
/// tool, from one query (as [`distance_outside`] tells, zero inside): a convex polyhedron's
/// nearest face plane for a point inside, a rounded shape's inner shape plus its border,
/// parry's projection otherwise.
pub(crate) fn boundary_point(
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    p: Vector,
) -> (Vector, bool) {
    let local = pose.inverse_transform_point(p);
    if let Some(poly) = shape.as_convex_polyhedron() {
        // Inside, the nearest face plane's projection. Outside by a hair too (within the
        // contact margin, or GJK's absolute tolerance on a small tool): parry takes such a
        // point for inside and its projection can land far away (a vertex 3.5e-7 m outside a
        // 7.5 mm hull's bottom edge was put 2 mm across the bottom face, and the plate,
        // dragged, blew up: a random case of `grazing_drag`); the plane's projection is within
        // that hair of the true nearest point.
        if let Some((n, d)) = closest_face(poly, local) {
            if d <= 0.0 || d <= (1e-4 * poly.local_aabb().extents().max_element()).max(2.5e-6) {
                return (pose.transform_point(local - n * d), d <= 0.0);
            }
        }
        return (shape.project_point(pose, p, false).point, false);
    }
    if let Some((inner, border)) = rounded(shape) {
        // The inner shape's nearest boundary point and the outward direction there, then the
        // border radius along it.
        let near = match inner.as_convex_polyhedron() {
            Some(poly) => face_projection(poly, local).map(|(q, n)| (q, n, true)),
            None => None,
        }
        .or_else(|| {
            let q = project_inner(inner, local, false);
            let d = local - q.point;
            let out = if q.is_inside { -d } else { d };
            out.try_normalize()
                .map(|n| (q.point, n, q.is_inside || d.length() <= border))
        });
        if let Some((q, n, inside)) = near {
            return (pose.transform_point(q + n * border), inside);
        }
    }
    let proj = shape.project_point(pose, p, false);
    (proj.point, proj.is_inside)
}

/// For `local` inside the convex polyhedron `poly`, the nearest point of its boundary (on the
/// nearest face plane) and that face's outward normal; `None` outside.
fn face_projection(
    poly: &parry3d::shape::ConvexPolyhedron,
    local: Vector,
) -> Option<(Vector, Vector)> {
    closest_face(poly, local)
        .filter(|(_, d)| *d <= 0.0)
        .map(|(n, d)| (local - n * d, n))
}

/// Where the ray from `p` (inside the tool, world) along the unit `d` leaves the tool. For a
/// convex polyhedron the nearest exit plane is used (parry's ray cast from inside a support
/// map is iterative and can stop early); other shapes are cast at a size parry's tolerances
/// suit.
pub(crate) fn exit_along(
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    p: Vector,
    d: Vector,
) -> Option<Vector> {
    let (local, dl) = (pose.inverse_transform_point(p), pose.rotation.inverse() * d);
    if let Some(poly) = shape.as_convex_polyhedron() {
        let t = face_planes(poly)
            .filter_map(|(n, v)| {
                let along = n.dot(dl);
                (along > 0.0).then(|| (-n.dot(local - v) / along).max(0.0))
            })
            .min_by(|a, b| a.total_cmp(b))?;
        return Some(p + d * t);
    }
    if let Some(t) = round_exit(shape, local, dl) {
        return Some(p + d * t);
    }
    // parry's cast from inside a support map works to absolute tolerances: on a cylinder of
    // 0.6 mm radius it finds nothing, on one of 6 m its exit is 10 cm off; other shapes are
    // cast scaled to a fifth of a unit (a capsule's exit is then good to 1e-7 of its size).
    // Support maps only: scaling a triangle mesh or a compound would copy it at every call.
    let size = shape.compute_local_aabb().extents().max_element();
    if shape.as_support_map().is_some() && !(0.05..=2.0).contains(&size) {
        if let Some((unit, scale)) = scaled(shape, size, 0.2) {
            return unit
                .cast_local_ray(&Ray::new(local * scale, dl), Real::MAX, false)
                .map(|t| p + d * (t / scale));
        }
    }
    shape
        .cast_ray(pose, &Ray::new(p, d), Real::MAX, false)
        .map(|t| p + d * t)
}

#[cfg(test)]
mod tests;
