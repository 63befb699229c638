//! Wavefront OBJ import ([`load_obj`], [`parse_obj`]).

use super::*;
/// Loads every object of a Wavefront OBJ file into one [`SurfaceMesh`] (see [`parse_obj`]).
/// Material libraries are not read.
///
/// # Errors
/// [`MeshingError::Io`] if the file cannot be opened, and the errors of [`parse_obj`].
pub fn load_obj(path: impl AsRef<Path>) -> Result<SurfaceMesh, MeshingError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).map_err(|source| MeshingError::Io {
        path: path.to_owned(),
        source,
    })?;
    read_obj(&mut std::io::BufReader::new(file))
}

/// Parses Wavefront OBJ text into one [`SurfaceMesh`].
///
/// All objects and groups are merged (their indices offset). Polygons are split into
/// triangle fans; points and lines are ignored, and so are faces that repeat a vertex.
/// Vertices are welded by OBJ position index: a position shared by faces with different
/// normals or texture coordinates stays one vertex, so the surface stays connected. Vertices
/// no face uses are dropped. The winding is the file's.
///
/// ```
/// let mesh = rapier_touch::surface::meshing::parse_obj(
///     "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 3 2\n",
/// ).unwrap();
/// assert_eq!((mesh.num_vertices(), mesh.num_triangles()), (3, 1));
/// ```
///
/// # Errors
/// [`MeshingError::Obj`] for malformed text, [`MeshingError::NonFinitePosition`] for a NaN or
/// infinite position, [`MeshingError::EmptyMesh`] if no triangle is left.
pub fn parse_obj(text: &str) -> Result<SurfaceMesh, MeshingError> {
    read_obj(&mut text.as_bytes())
}

fn read_obj(reader: &mut impl BufRead) -> Result<SurfaceMesh, MeshingError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) =
        tobj::load_obj_buf(reader, &options, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(MeshingError::Obj)?;

    let mut positions: Vec<Vector> = Vec::new();
    let mut triangles: Vec<[usize; 3]> = Vec::new();
    for model in &models {
        let mesh = &model.mesh;
        let offset = positions.len();
        for p in mesh.positions.chunks_exact(3) {
            let v = Vector::new(p[0], p[1], p[2]);
            if !v.is_finite() {
                return Err(MeshingError::NonFinitePosition {
                    vertex: positions.len(),
                });
            }
            positions.push(v);
        }
        let count = positions.len() - offset;
        for t in mesh.indices.chunks_exact(3) {
            let t = [t[0], t[1], t[2]].map(|i| i as usize);
            if t.iter().any(|&i| i >= count) {
                return Err(MeshingError::Obj(tobj::LoadError::FaceVertexOutOfBounds));
            }
            if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                continue;
            }
            triangles.push(t.map(|i| i + offset));
        }
    }
    compacted(positions, triangles)
}

/// A surface from a triangle soup read from a file: degenerate triangles already dropped, the
/// vertices no triangle uses removed (the others keep their file order).
pub(in crate::surface) fn compacted(
    positions: Vec<Vector>,
    triangles: Vec<[usize; 3]>,
) -> Result<SurfaceMesh, MeshingError> {
    if triangles.is_empty() {
        return Err(MeshingError::EmptyMesh);
    }

    // Compact: keep the vertices some triangle uses, in file order.
    let mut new_index = vec![usize::MAX; positions.len()];
    for t in &triangles {
        for &i in t {
            new_index[i] = 0;
        }
    }
    let mut vertices = Vec::new();
    for (i, p) in positions.iter().enumerate() {
        if new_index[i] == 0 {
            new_index[i] = vertices.len();
            vertices.push(*p);
        }
    }
    if vertices.len() as u64 > u32::MAX as u64 {
        return Err(MeshingError::TooManyVertices {
            estimated: vertices.len() as u64,
            max: u32::MAX as u64,
        });
    }
    let triangles = triangles
        .iter()
        .map(|t| t.map(|i| new_index[i] as u32))
        .collect();
    Ok(SurfaceMesh {
        vertices,
        triangles,
    })
}
