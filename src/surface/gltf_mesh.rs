//! Binary glTF (`.glb`) surfaces, beside OBJ ([`super::meshing::load_obj`]), read with the
//! `gltf` crate: the triangles of every mesh the default scene places, in world coordinates.

use super::meshing::{compacted, MeshingError, SurfaceMesh};
use crate::math::Vector;
use gltf::buffer::Source;
use gltf::mesh::Mode;
use std::path::Path;

/// Reads a `.glb` file as one surface: see [`parse_glb`].
///
/// # Errors
/// [`MeshingError::Io`] when the file cannot be read, and those of [`parse_glb`].
pub fn load_glb(path: impl AsRef<Path>) -> Result<SurfaceMesh, MeshingError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| MeshingError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_glb(&bytes)
}

/// Parses a binary glTF 2.0 asset (a `.glb`) as one surface.
///
/// - Every mesh the default scene (else the first scene) places is read, each instance moved by
///   its node's world transform; an asset with no scene gives its meshes in their own frames.
/// - Triangle primitives only (`TRIANGLES`, `TRIANGLE_STRIP` and `TRIANGLE_FAN` are
///   unrolled); points and lines are left out, as the OBJ reader leaves them out.
/// - Non-indexed primitives are read in vertex order; degenerate triangles (a repeated index)
///   are dropped and unused vertices removed, as for OBJ. Vertices are not welded across
///   primitives: [`MassSpringSurfaceBuilder`](super::MassSpringSurfaceBuilder) treats the
///   result as given.
/// - Buffers must be the `.glb`'s own binary chunk: external files and data URIs are
///   [`MeshingError::GltfExternalBuffer`].
///
/// # Errors
/// [`MeshingError::Gltf`] for a malformed or invalid asset,
/// [`MeshingError::GltfExternalBuffer`], [`MeshingError::GltfNoPositions`],
/// [`MeshingError::GltfIndexOutOfRange`],
/// [`MeshingError::NonFinitePosition`], and [`MeshingError::EmptyMesh`] when no triangle is
/// left.
pub fn parse_glb(bytes: &[u8]) -> Result<SurfaceMesh, MeshingError> {
    let gltf = gltf::Gltf::from_slice(bytes).map_err(MeshingError::Gltf)?;
    // The meshes to read, each with the world transform of the node placing it.
    let mut placed: Vec<(gltf::Mesh, [[f32; 4]; 4])> = Vec::new();
    match gltf.default_scene().or_else(|| gltf.scenes().next()) {
        Some(scene) => {
            let mut stack: Vec<(gltf::Node, [[f32; 4]; 4])> =
                scene.nodes().map(|n| (n, IDENTITY)).collect();
            while let Some((node, parent)) = stack.pop() {
                let world = mul(&parent, &node.transform().matrix());
                if let Some(mesh) = node.mesh() {
                    placed.push((mesh, world));
                }
                stack.extend(node.children().map(|c| (c, world)));
            }
        }
        None => placed.extend(gltf.meshes().map(|m| (m, IDENTITY))),
    }
    let blob = gltf.blob.as_deref();
    let mut positions: Vec<Vector> = Vec::new();
    let mut triangles: Vec<[usize; 3]> = Vec::new();
    for (mesh, world) in &placed {
        for (pi, primitive) in mesh.primitives().enumerate() {
            let mode = primitive.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                continue;
            }
            // Positions and indices both (an index buffer left unread would turn an indexed
            // primitive into an unindexed one).
            for buffer in primitive
                .attributes()
                .map(|(_, a)| a)
                .chain(primitive.indices())
                .filter_map(|a| a.view())
                .map(|v| v.buffer())
            {
                if !matches!(buffer.source(), Source::Bin) {
                    return Err(MeshingError::GltfExternalBuffer {
                        buffer: buffer.index(),
                    });
                }
            }
            let reader = primitive.reader(|b| match b.source() {
                Source::Bin => blob,
                Source::Uri(_) => None,
            });
            let Some(read) = reader.read_positions() else {
                return Err(MeshingError::GltfNoPositions {
                    mesh: mesh.index(),
                    primitive: pi,
                });
            };
            let offset = positions.len();
            for p in read {
                let v = transform(world, p);
                if !v.is_finite() {
                    return Err(MeshingError::NonFinitePosition {
                        vertex: positions.len(),
                    });
                }
                positions.push(v);
            }
            let count = positions.len() - offset;
            let indices: Vec<usize> = match reader.read_indices() {
                Some(i) => i.into_u32().map(|i| i as usize).collect(),
                None => (0..count).collect(),
            };
            if indices.iter().any(|&i| i >= count) {
                return Err(MeshingError::GltfIndexOutOfRange {
                    mesh: mesh.index(),
                    primitive: pi,
                });
            }
            let unrolled: Vec<[usize; 3]> = match mode {
                Mode::TriangleStrip => (2..indices.len())
                    .map(|k| {
                        let (a, b, c) = (indices[k - 2], indices[k - 1], indices[k]);
                        if k % 2 == 0 {
                            [a, b, c]
                        } else {
                            [b, a, c]
                        }
                    })
                    .collect(),
                Mode::TriangleFan => (2..indices.len())
                    .map(|k| [indices[0], indices[k - 1], indices[k]])
                    .collect(),
                _ => indices
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect(),
            };
            // A node mirrored by a negative scale turns its triangles inside out: keep them
            // facing outward.
            let flip = det3(world) < 0.0;
            for t in unrolled {
                if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                    continue;
                }
                let t = if flip { [t[0], t[2], t[1]] } else { t };
                triangles.push(t.map(|i| i + offset));
            }
        }
    }
    compacted(positions, triangles)
}

const IDENTITY: [[f32; 4]; 4] = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// `a · b` for glTF's column-major matrices (`m[column][row]`).
fn mul(a: &[[f32; 4]; 4], b: &[[f32; 4]; 4]) -> [[f32; 4]; 4] {
    let mut m = [[0.0; 4]; 4];
    for (c, col) in m.iter_mut().enumerate() {
        for (r, v) in col.iter_mut().enumerate() {
            *v = (0..4).map(|k| a[k][r] * b[c][k]).sum();
        }
    }
    m
}

fn transform(m: &[[f32; 4]; 4], p: [f32; 3]) -> Vector {
    Vector::new(
        m[0][0] * p[0] + m[1][0] * p[1] + m[2][0] * p[2] + m[3][0],
        m[0][1] * p[0] + m[1][1] * p[1] + m[2][1] * p[2] + m[3][1],
        m[0][2] * p[0] + m[1][2] * p[1] + m[2][2] * p[2] + m[3][2],
    )
}

/// The determinant of the linear part.
fn det3(m: &[[f32; 4]; 4]) -> f32 {
    let c = |i: usize| Vector::new(m[i][0], m[i][1], m[i][2]);
    c(0).dot(c(1).cross(c(2)))
}
