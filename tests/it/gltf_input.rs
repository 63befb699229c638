//! Binary glTF surfaces (`surface::meshing::parse_glb`): a `.glb` written here by hand from a
//! known mesh, placed by a node with a translation, a rotation and a scale under a parent node,
//! reads back as that mesh moved by the composed transform (computed here with glam), whatever
//! the primitive's form; bad assets are errors.

use rapier_touch::prelude::*;
use rapier_touch::surface::meshing::{box_surface, parse_glb, MeshingError, SurfaceMesh};

/// A `.glb` holding `mesh` as one primitive (`mode`, indices written as given), placed by
/// `child` under `parent` (TRS each).
fn glb(mesh: &SurfaceMesh, indices: &[u32], mode: u32, parent: &str, child: &str) -> Vec<u8> {
    glb_with(mesh, indices, mode, parent, child, false)
}

/// [`glb`], with the indices' buffer view pointing into an external file when
/// `external_indices`.
fn glb_with(
    mesh: &SurfaceMesh,
    indices: &[u32],
    mode: u32,
    parent: &str,
    child: &str,
    external_indices: bool,
) -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    for v in &mesh.vertices {
        for c in [v.x, v.y, v.z] {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let positions_len = bin.len();
    for i in indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let (lo, hi) = mesh.vertices.iter().fold(
        (Vector::splat(f32::MAX), Vector::splat(f32::MIN)),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    );
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"children":[1],{parent}}},{{"mesh":0,{child}}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":{mode}}}]}}],
        "accessors":[
          {{"bufferView":0,"componentType":5126,"count":{nv},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}},
          {{"bufferView":1,"componentType":5125,"count":{ni},"type":"SCALAR"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{positions_len}}},
          {{"buffer":{ib},"byteOffset":{io},"byteLength":{il}}}],
        "buffers":[{{"byteLength":{bl}}}{extra}]}}"#,
        lo.x,
        lo.y,
        lo.z,
        hi.x,
        hi.y,
        hi.z,
        nv = mesh.vertices.len(),
        ni = indices.len(),
        il = indices.len() * 4,
        bl = bin.len(),
        ib = if external_indices { 1 } else { 0 },
        io = if external_indices { 0 } else { positions_len },
        extra = if external_indices {
            format!(
                r#",{{"byteLength":{},"uri":"indices.bin"}}"#,
                indices.len() * 4
            )
        } else {
            String::new()
        },
    );
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

const PARENT: &str = r#""translation":[1.0,-2.0,0.5],"scale":[2.0,2.0,2.0]"#;
const CHILD: &str = r#""translation":[0.0,0.25,0.0],"rotation":[0.0,0.38268343,0.0,0.9238795]"#;

/// The world position glTF gives a child-local point: parent TRS after child TRS.
fn placed(p: Vector) -> Vector {
    let parent = glamx::Mat4::from_scale_rotation_translation(
        glamx::Vec3::splat(2.0),
        glamx::Quat::IDENTITY,
        glamx::Vec3::new(1.0, -2.0, 0.5),
    );
    let child = glamx::Mat4::from_scale_rotation_translation(
        glamx::Vec3::ONE,
        glamx::Quat::from_rotation_y(std::f32::consts::FRAC_PI_4),
        glamx::Vec3::new(0.0, 0.25, 0.0),
    );
    let q = (parent * child).transform_point3(glamx::Vec3::new(p.x, p.y, p.z));
    Vector::new(q.x, q.y, q.z)
}

#[test]
fn a_glb_reads_back_as_the_mesh_its_nodes_place() {
    let mesh = box_surface(Vector::new(0.3, 0.2, 0.1), 3);
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let read = parse_glb(&glb(&mesh, &indices, 4, PARENT, CHILD)).unwrap();
    assert_eq!(read.triangles, mesh.triangles);
    assert_eq!(read.vertices.len(), mesh.vertices.len());
    for (r, v) in read.vertices.iter().zip(&mesh.vertices) {
        assert!(
            (*r - placed(*v)).length() < 1e-5,
            "{r:?} vs {:?}",
            placed(*v)
        );
    }
    // The surface builds, and its area is the box's, scaled by 2² (rotation and translation
    // change nothing).
    let area = |m: &SurfaceMesh| -> f32 {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.vertices[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    };
    assert!((area(&read) - 4.0 * area(&mesh)).abs() < 1e-4 * area(&read));
    assert!(MassSpringSurfaceBuilder::from_mesh(&read).build().is_ok());
}

#[test]
fn strips_and_fans_unroll_into_the_same_triangles() {
    // A quad (two triangles) as a list, a strip and a fan.
    let quad = SurfaceMesh {
        vertices: vec![
            Vector::new(0.0, 0.0, 0.0),
            Vector::new(1.0, 0.0, 0.0),
            Vector::new(1.0, 0.0, 1.0),
            Vector::new(0.0, 0.0, 1.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    let area = |m: &SurfaceMesh| -> Vector {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.vertices[i as usize]);
                0.5 * (b - a).cross(c - a)
            })
            .sum()
    };
    let identity = r#""translation":[0.0,0.0,0.0]"#;
    let list = parse_glb(&glb(&quad, &[0, 1, 2, 0, 2, 3], 4, identity, identity)).unwrap();
    let strip = parse_glb(&glb(&quad, &[1, 2, 0, 3], 5, identity, identity)).unwrap();
    let fan = parse_glb(&glb(&quad, &[0, 1, 2, 3], 6, identity, identity)).unwrap();
    for m in [&list, &strip, &fan] {
        assert_eq!(m.triangles.len(), 2);
        // Same oriented area: one square metre facing -y, as the list's.
        assert!((area(m) - area(&quad)).length() < 1e-6, "{:?}", area(m));
    }
}

#[test]
fn bad_glbs_are_errors() {
    let mesh = box_surface(Vector::splat(0.5), 1);
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let good = glb(&mesh, &indices, 4, PARENT, CHILD);
    // Truncated, and not glTF at all.
    assert!(matches!(
        parse_glb(&good[..good.len() / 2]),
        Err(MeshingError::Gltf(_))
    ));
    assert!(matches!(
        parse_glb(b"solid cube"),
        Err(MeshingError::Gltf(_))
    ));
    // An index past the vertices.
    let mut bad = indices.clone();
    bad[4] = 10_000;
    assert!(matches!(
        parse_glb(&glb(&mesh, &bad, 4, PARENT, CHILD)),
        Err(MeshingError::GltfIndexOutOfRange { .. })
    ));
    // Indices in an external file: refused, not read as an unindexed primitive.
    assert!(matches!(
        parse_glb(&glb_with(&mesh, &indices, 4, PARENT, CHILD, true)),
        Err(MeshingError::GltfExternalBuffer { buffer: 1 })
    ));
    // Points only: no triangle.
    assert!(matches!(
        parse_glb(&glb(&mesh, &indices, 0, PARENT, CHILD)),
        Err(MeshingError::EmptyMesh)
    ));
    // A NaN position.
    let mut nan = mesh.clone();
    nan.vertices[3].y = f32::NAN;
    let r = parse_glb(&glb(&nan, &indices, 4, PARENT, CHILD));
    assert!(
        matches!(
            r,
            Err(MeshingError::NonFinitePosition { .. }) | Err(MeshingError::Gltf(_))
        ),
        "{r:?}"
    );
}
