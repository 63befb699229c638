//! The [`Camera`]: look-at, perspective or orthographic, fitted to a scene.

use super::*;

/// How a [`Camera`] projects.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Projection {
    /// Perspective with this vertical field of view (radians).
    Perspective {
        /// Vertical field of view in radians.
        fov_y: Real,
    },
    /// Orthographic, showing `2 half_height` world units from bottom to top.
    Orthographic {
        /// Half the world height the picture shows.
        half_height: Real,
    },
}

/// A look-at camera: the picture's centre is `target`, seen from `eye`, `up` pointing up.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Camera {
    /// Where the camera is.
    pub eye: Vector,
    /// The point at the picture's centre.
    pub target: Vector,
    /// The world direction that appears upward.
    pub up: Vector,
    /// Perspective or orthographic.
    pub projection: Projection,
}

/// `x` if it is finite and in `lo..hi`, else `default`.
pub(super) fn valid(x: Real, lo: Real, hi: Real, default: Real) -> Real {
    if x.is_finite() && x > lo && x < hi {
        x
    } else {
        default
    }
}

pub(super) const DEFAULT_FOV: Real = 0.6;

impl Camera {
    /// A perspective camera (0.6 rad, about 35°, vertical field of view) at `eye` looking at
    /// `target`.
    pub fn look_at(eye: Vector, target: Vector, up: Vector) -> Self {
        let projection = Projection::Perspective { fov_y: DEFAULT_FOV };
        Camera {
            eye,
            target,
            up,
            projection,
        }
    }

    /// A camera looking along `direction` that frames all finite `points` (with a small margin)
    /// in a picture of the given `aspect` (width / height). An orthographic `projection` gets
    /// its `half_height` computed; a perspective one keeps its field of view and gets its
    /// distance. No finite point: a unit region around the origin is framed.
    pub fn fit(
        points: impl IntoIterator<Item = Vector>,
        direction: Vector,
        up: Vector,
        projection: Projection,
        aspect: Real,
    ) -> Self {
        let (r, u, f) = basis(direction, up);
        let mut pts: Vec<Vector> = points.into_iter().filter(|p| p.is_finite()).collect();
        if pts.is_empty() {
            pts = vec![Vector::splat(-0.5), Vector::splat(0.5)];
        }
        let aspect = valid(aspect, 0.0, Real::INFINITY, 1.0);
        let lo = pts.iter().fold(Vector::MAX, |m, p| m.min(*p));
        let hi = pts.iter().fold(Vector::MIN, |m, p| m.max(*p));
        let mut c = 0.5 * (lo + hi);
        let (mut x0, mut x1, mut y0, mut y1) = (Real::MAX, Real::MIN, Real::MAX, Real::MIN);
        for p in &pts {
            let (x, y) = ((*p - c).dot(r), (*p - c).dot(u));
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        c += r * 0.5 * (x0 + x1) + u * 0.5 * (y0 + y1);
        let (margin, radius) = (1.08, (hi - lo).length().max(1e-6));
        let (eye, projection) = match projection {
            Projection::Orthographic { .. } => {
                let half = (0.5 * (y1 - y0)).max(0.5 * (x1 - x0) / aspect).max(1e-6);
                let projection = Projection::Orthographic {
                    half_height: half * margin,
                };
                (c - f * 2.0 * radius, projection)
            }
            Projection::Perspective { fov_y } => {
                let fov_y = valid(fov_y, 0.01, 3.0, DEFAULT_FOV);
                let t = (0.5 * fov_y).tan();
                let mut dist: Real = 1e-3 * radius;
                for p in &pts {
                    let d = *p - c;
                    let need = (d.dot(u).abs() / t).max(d.dot(r).abs() / (t * aspect));
                    dist = dist
                        .max(need * margin - d.dot(f))
                        .max(0.01 * radius - d.dot(f));
                }
                (c - f * dist, Projection::Perspective { fov_y })
            }
        };
        Camera {
            eye,
            target: c,
            up,
            projection,
        }
    }

    /// The same view, `factor` times wider (a factor above 1 zooms out): an orthographic
    /// camera's `half_height` is scaled, a perspective camera moves along its line of sight.
    pub fn zoomed(mut self, factor: Real) -> Self {
        let factor = valid(factor, 0.0, Real::INFINITY, 1.0);
        match &mut self.projection {
            Projection::Orthographic { half_height } => *half_height *= factor,
            Projection::Perspective { .. } => {
                self.eye = self.target + (self.eye - self.target) * factor;
            }
        }
        self
    }

    /// World units per pixel at the target's depth, in a picture `height` pixels high.
    pub fn world_per_pixel(&self, height: u32) -> Real {
        let half = match self.projection {
            Projection::Orthographic { half_height } => half_height,
            Projection::Perspective { fov_y } => {
                (self.target - self.eye).length() * (0.5 * fov_y).tan()
            }
        };
        2.0 * half / height.max(1) as Real
    }

    /// Picture coordinates (pixels, `y` down) and view depth of `p`, or `None` if it is behind
    /// a perspective camera or not finite.
    pub fn project(&self, p: Vector, width: u32, height: u32) -> Option<(f32, f32, f32)> {
        let (r, u, f) = basis(self.target - self.eye, self.up);
        let d = p - self.eye;
        let (x, y, z) = (d.dot(r), d.dot(u), d.dot(f));
        let scale = match self.projection {
            Projection::Perspective { fov_y } if z > 1e-6 => 1.0 / (z * (0.5 * fov_y).tan()),
            Projection::Perspective { .. } => return None,
            Projection::Orthographic { half_height } => 1.0 / half_height,
        };
        let h = 0.5 * height as f32;
        let s = (0.5 * width as f32 + x * scale * h, h - y * scale * h, z);
        (s.0.is_finite() && s.1.is_finite() && z.is_finite()).then_some(s)
    }
}

/// Right, up and forward unit vectors of a view along `forward` with `up` as the up hint.
pub(super) fn basis(forward: Vector, up: Vector) -> (Vector, Vector, Vector) {
    let f = forward.normalize_or(Vector::NEG_Z);
    let mut r = f.cross(up).normalize_or_zero();
    if r == Vector::ZERO {
        r = f.any_orthonormal_vector();
    }
    (r, r.cross(f), f)
}
