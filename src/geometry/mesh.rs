//! Triangle meshes read from CAD exports — OBJ ([`tobj`]), STL ASCII and binary ([`stl_io`]),
//! glTF/GLB ([`gltf`]) — checked for what the simulation needs, and the mass properties of a
//! closed mesh (divergence theorem). f64, Bevy-free.
//!
//! A file becomes one or more named *components*: each glTF node that carries a mesh (named by
//! the node), each OBJ object or group (named by it), or the whole STL file. Components with the
//! same name are merged. Vertices are returned in the part frame: the glTF node transforms
//! (accumulated from the scene root) and the uniform `scale` are applied.
//!
//! What is refused, with the file and the element named: a path that is not a regular file (a
//! FIFO, a device or a directory is refused before it is opened, so nothing can block), a file
//! larger than [`MAX_MESH_FILE_BYTES`], an unknown extension, a parse error, a glTF buffer that
//! is missing or shorter than declared, a non-triangle glTF primitive, an empty mesh, a
//! non-finite or too distant vertex, an index out of range, a degenerate (zero-area) triangle,
//! more triangles than the stated limit.

use nalgebra::{Matrix3, Matrix4, Point3, Vector3};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// Largest mesh file (or external glTF buffer) read, bytes (256 MiB).
pub const MAX_MESH_FILE_BYTES: u64 = 256 << 20;

/// Default limit on a mesh part's triangles (all its components together).
pub const DEFAULT_MAX_TRIANGLES: u32 = 200_000;

/// Largest distance of a vertex from the part frame's origin, m.
pub const MAX_VERTEX_M: f64 = 1e4;

/// A triangle is degenerate when its area is below this fraction of the square of the
/// component's bounding-box diagonal.
pub const DEGENERATE_AREA_REL: f64 = 1e-14;

/// Deepest glTF node hierarchy followed.
const MAX_NODE_DEPTH: usize = 64;

/// One named piece of a mesh file, in the part frame.
#[derive(Clone, PartialEq)]
pub struct MeshComponent {
    /// Its convex decomposition for rapier, made once (by the simulation layer) and shared by
    /// every run of the scene.
    pub decomposition: std::sync::OnceLock<Decomposition>,
    /// Name (glTF node, OBJ object, or the STL file's stem).
    pub name: String,
    /// Where the component's frame sits in the part frame, m: the centre of its vertices'
    /// bounding box, so that bounding spheres about the collider origin are tight (the
    /// monitor prunes part pairs by them). Zero until [`MeshComponent::recentre`].
    pub offset_m: Vector3<f64>,
    /// Vertices, component frame (the part frame shifted by `offset_m`), m.
    pub vertices_m: Vec<Point3<f64>>,
    /// Triangles (indices into `vertices_m`), counter-clockwise seen from outside for a closed
    /// mesh.
    pub triangles: Vec<[u32; 3]>,
}

impl std::fmt::Debug for MeshComponent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "MeshComponent {{ name: {:?}, vertices: {}, triangles: {} }}",
            self.name,
            self.vertices_m.len(),
            self.triangles.len()
        )
    }
}

impl MeshComponent {
    /// Moves the component's frame to the centre of its bounding box (`offset_m`).
    pub fn recentre(&mut self) {
        let (mut lo, mut hi) = (Vector3::repeat(f64::MAX), Vector3::repeat(f64::MIN));
        for v in &self.vertices_m {
            lo = lo.inf(&v.coords);
            hi = hi.sup(&v.coords);
        }
        if self.vertices_m.is_empty() {
            return;
        }
        let c = (lo + hi) / 2.0;
        for v in &mut self.vertices_m {
            v.coords -= c;
        }
        self.offset_m += c;
    }

    /// Radius of a sphere about the part-frame origin holding every vertex (and so every
    /// triangle), m.
    pub fn bounding_radius_m(&self) -> f64 {
        self.vertices_m
            .iter()
            .map(|p| p.coords.norm())
            .fold(0.0, f64::max)
    }

    /// The three corners of triangle `k`.
    pub fn corners(&self, k: usize) -> [Point3<f64>; 3] {
        let t = self.triangles[k];
        t.map(|i| self.vertices_m[i as usize])
    }
}

/// One convex piece: vertices (m) and triangles.
pub type ConvexPiece = (Vec<Point3<f64>>, Vec<[u32; 3]>);

/// A convex decomposition of a component: convex pieces (vertices and triangles, part frame)
/// and how far it deviates from the mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Decomposition {
    /// Convex pieces: vertices (m) and triangles.
    pub hulls: Vec<ConvexPiece>,
    /// Largest deviation found between the pieces' surfaces and the mesh, m (see the
    /// simulation layer's `sim::mesh` for how it is measured).
    pub max_deviation_m: f64,
}

/// A mesh file read and checked: its components, in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshFile {
    /// The components.
    pub components: Vec<std::sync::Arc<MeshComponent>>,
}

/// What a mesh file may be, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ.
    Obj,
    /// STL, ASCII or binary.
    Stl,
    /// glTF 2.0, JSON (`.gltf`) or binary (`.glb`).
    Gltf,
}

impl MeshFormat {
    /// The format of a file name, by its extension (case-insensitive).
    pub fn of(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Some(Self::Obj),
            "stl" => Some(Self::Stl),
            "gltf" | "glb" => Some(Self::Gltf),
            _ => None,
        }
    }
}

/// Reads a whole file that must be a regular file of at most [`MAX_MESH_FILE_BYTES`]; the
/// type is checked on the path's metadata before the file is opened, so a FIFO or a device
/// is refused without blocking.
pub fn read_regular_file(path: &Path) -> Result<Vec<u8>, String> {
    let meta =
        std::fs::metadata(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if !meta.is_file() {
        return Err(format!(
            "{} is not a regular file (a directory, FIFO, socket or device is not read)",
            path.display()
        ));
    }
    if meta.len() > MAX_MESH_FILE_BYTES {
        return Err(format!(
            "{} is {} bytes, more than the limit of {MAX_MESH_FILE_BYTES} bytes",
            path.display(),
            meta.len()
        ));
    }
    let f =
        std::fs::File::open(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut bytes = Vec::new();
    f.take(MAX_MESH_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if bytes.len() as u64 > MAX_MESH_FILE_BYTES {
        return Err(format!(
            "{} is larger than the limit of {MAX_MESH_FILE_BYTES} bytes",
            path.display()
        ));
    }
    Ok(bytes)
}

/// Reads a mesh file, keeps the components named in `nodes` (all when empty), scales it, and
/// checks it ([`check_component`]) with at most `max_triangles` triangles in all. Errors name
/// the file and the element (component, triangle, vertex, buffer).
pub fn load_mesh_file(
    path: &Path,
    scale: f64,
    nodes: &[String],
    max_triangles: u32,
) -> Result<MeshFile, String> {
    let Some(format) = MeshFormat::of(path) else {
        return Err(format!(
            "{}: unknown mesh extension (expected .obj, .stl, .gltf or .glb)",
            path.display()
        ));
    };
    let bytes = read_regular_file(path)?;
    let file = path.display().to_string();
    let raw = match format {
        MeshFormat::Obj => read_obj(&bytes).map_err(|e| format!("{file}: {e}"))?,
        MeshFormat::Stl => {
            let stem = path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("mesh")
                .to_string();
            read_stl(&bytes, stem).map_err(|e| format!("{file}: {e}"))?
        }
        MeshFormat::Gltf => read_gltf(&bytes, path).map_err(|e| format!("{file}: {e}"))?,
    };
    // Merge components of the same name, in order of first appearance.
    let mut merged: Vec<MeshComponent> = Vec::new();
    let mut index: BTreeMap<String, usize> = BTreeMap::new();
    for c in raw {
        match index.get(&c.name) {
            Some(&k) => {
                let m = &mut merged[k];
                let base = m.vertices_m.len() as u64;
                if base + c.vertices_m.len() as u64 > u64::from(u32::MAX) {
                    return Err(format!("{file}: component {:?}: too many vertices", c.name));
                }
                m.vertices_m.extend(c.vertices_m);
                m.triangles
                    .extend(c.triangles.iter().map(|t| t.map(|i| i + base as u32)));
            }
            None => {
                index.insert(c.name.clone(), merged.len());
                merged.push(c);
            }
        }
    }
    let available = || {
        merged
            .iter()
            .map(|c| format!("{:?}", c.name))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut selected = if nodes.is_empty() {
        merged.clone()
    } else {
        let mut out = Vec::new();
        for n in nodes {
            match merged.iter().find(|c| &c.name == n) {
                Some(c) => out.push(c.clone()),
                None => {
                    return Err(format!(
                        "{file}: no component (glTF node with a mesh, OBJ object) named {n:?}; \
                         the file has {}",
                        available()
                    ));
                }
            }
        }
        out
    };
    if selected.is_empty() {
        return Err(format!("{file}: the file holds no triangles"));
    }
    // Several components become colliders named after them (contacts.csv, events, summaries):
    // the one name rule of every scene name applies to a name from a file as well.
    if selected.len() > 1 {
        for c in &selected {
            if let Some(p) = crate::scene::validate::name_problem(&c.name) {
                return Err(format!(
                    "{file}: component {:?} (glTF node, OBJ object) names a part: {p}; rename it \
                     in the file, or select one component with `nodes` (then the part's name is used)",
                    c.name
                ));
            }
        }
    }
    let total: u64 = selected.iter().map(|c| c.triangles.len() as u64).sum();
    if total > u64::from(max_triangles) {
        return Err(format!(
            "{file}: {total} triangles, more than the limit of {max_triangles} (`max_triangles`)"
        ));
    }
    for c in &mut selected {
        for v in &mut c.vertices_m {
            *v *= scale;
        }
        check_component(c).map_err(|e| format!("{file}: component {:?}: {e}", c.name))?;
        c.recentre();
    }
    Ok(MeshFile {
        components: selected.into_iter().map(std::sync::Arc::new).collect(),
    })
}

/// Checks a component: at least one triangle, finite vertices within [`MAX_VERTEX_M`] of the
/// origin, indices in range, no degenerate triangle (area below [`DEGENERATE_AREA_REL`] of the
/// squared bounding-box diagonal). Vertices no triangle uses are allowed.
pub fn check_component(c: &MeshComponent) -> Result<(), String> {
    if c.triangles.is_empty() {
        return Err("no triangles (an empty mesh)".into());
    }
    for (k, v) in c.vertices_m.iter().enumerate() {
        if !v.coords.iter().all(|x| x.is_finite()) {
            return Err(format!("vertex {k} is not finite ({v:?})"));
        }
        if v.coords.norm() > MAX_VERTEX_M {
            return Err(format!(
                "vertex {k} is {:e} m from the part origin, beyond the limit of {MAX_VERTEX_M:e} m",
                v.coords.norm()
            ));
        }
    }
    let n = c.vertices_m.len();
    let (mut lo, mut hi) = (Vector3::repeat(f64::MAX), Vector3::repeat(f64::MIN));
    for (k, t) in c.triangles.iter().enumerate() {
        if let Some(i) = t.iter().find(|i| **i as usize >= n) {
            return Err(format!(
                "triangle {k} uses vertex {i}, but there are {n} vertices"
            ));
        }
        for i in t {
            let p = c.vertices_m[*i as usize].coords;
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
    }
    let diag2 = (hi - lo).norm_squared();
    for k in 0..c.triangles.len() {
        let [a, b, d] = c.corners(k);
        let area = 0.5 * (b - a).cross(&(d - a)).norm();
        if area.is_nan() || area <= DEGENERATE_AREA_REL * diag2 {
            return Err(format!(
                "triangle {k} (vertices {:?}) is degenerate: area {area:e} m²",
                c.triangles[k]
            ));
        }
    }
    Ok(())
}

fn read_obj(bytes: &[u8]) -> Result<Vec<MeshComponent>, String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let mut reader = std::io::BufReader::new(bytes);
    // Material libraries are never opened: only geometry is used.
    let (models, _) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| format!("OBJ parse error: {e}"))?;
    let mut out = Vec::new();
    for (k, m) in models.iter().enumerate() {
        let name = if m.name.is_empty() || m.name == "unnamed_object" {
            format!("object{k}")
        } else {
            m.name.clone()
        };
        let p = &m.mesh.positions;
        if !p.len().is_multiple_of(3) || !m.mesh.indices.len().is_multiple_of(3) {
            return Err(format!("object `{name}`: incomplete position or face data"));
        }
        out.push(MeshComponent {
            decomposition: Default::default(),
            offset_m: Vector3::zeros(),
            name,
            vertices_m: p
                .chunks_exact(3)
                .map(|c| Point3::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2])))
                .collect(),
            triangles: m
                .mesh
                .indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
        });
    }
    Ok(out)
}

fn read_stl(bytes: &[u8], name: String) -> Result<Vec<MeshComponent>, String> {
    let mut cur = std::io::Cursor::new(bytes);
    let mesh = stl_io::read_stl(&mut cur).map_err(|e| format!("STL parse error: {e}"))?;
    let mut triangles = Vec::with_capacity(mesh.faces.len());
    for (k, f) in mesh.faces.iter().enumerate() {
        let mut t = [0u32; 3];
        for (o, i) in t.iter_mut().zip(f.vertices) {
            *o = u32::try_from(i).map_err(|_| format!("facet {k}: vertex index {i} too large"))?;
        }
        triangles.push(t);
    }
    Ok(vec![MeshComponent {
        decomposition: Default::default(),
        offset_m: Vector3::zeros(),
        name,
        vertices_m: mesh
            .vertices
            .iter()
            .map(|v| Point3::new(f64::from(v.0[0]), f64::from(v.0[1]), f64::from(v.0[2])))
            .collect(),
        triangles,
    }])
}

/// The bytes of every buffer of a glTF document: the GLB binary chunk, a base64 `data:` URI,
/// or a plain relative file next to the glTF file (no absolute path, no `..`), each at least
/// as long as the document declares.
fn gltf_buffers(g: &gltf::Gltf, path: &Path) -> Result<Vec<Vec<u8>>, String> {
    use base64::Engine;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut out = Vec::new();
    for b in g.document.buffers() {
        let k = b.index();
        let data = match b.source() {
            gltf::buffer::Source::Bin => g
                .blob
                .clone()
                .ok_or_else(|| format!("buffer {k}: the GLB binary chunk is missing"))?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let (_, payload) = uri
                    .split_once(";base64,")
                    .ok_or_else(|| format!("buffer {k}: a data URI must be base64"))?;
                base64::engine::general_purpose::STANDARD
                    .decode(payload)
                    .map_err(|e| format!("buffer {k}: bad base64 data: {e}"))?
            }
            gltf::buffer::Source::Uri(uri) => {
                let rel = Path::new(uri);
                if rel.is_absolute()
                    || rel
                        .components()
                        .any(|c| !matches!(c, std::path::Component::Normal(_)))
                {
                    return Err(format!(
                        "buffer {k}: `{uri}` must be a plain relative path next to the glTF file"
                    ));
                }
                read_regular_file(&dir.join(rel))
                    .map_err(|e| format!("buffer {k} (`{uri}`) is missing or unreadable: {e}"))?
            }
        };
        if data.len() < b.length() {
            return Err(format!(
                "buffer {k} has {} bytes, the document declares {}",
                data.len(),
                b.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

fn read_gltf(bytes: &[u8], path: &Path) -> Result<Vec<MeshComponent>, String> {
    let g = gltf::Gltf::from_slice(bytes).map_err(|e| format!("glTF parse error: {e}"))?;
    let buffers = gltf_buffers(&g, path)?;
    let doc = &g.document;
    let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return Err("the glTF file has no scene".into());
    };
    let mut out = Vec::new();
    let mut stack: Vec<(gltf::Node, Matrix4<f64>, usize)> =
        scene.nodes().map(|n| (n, Matrix4::identity(), 0)).collect();
    stack.reverse();
    let mut visited = 0usize;
    while let Some((node, parent, depth)) = stack.pop() {
        visited += 1;
        if depth > MAX_NODE_DEPTH || visited > 1 << 20 {
            return Err(format!(
                "node {}: the node hierarchy is deeper than {MAX_NODE_DEPTH} levels or cyclic",
                node.index()
            ));
        }
        let m = node.transform().matrix();
        let local = Matrix4::from_fn(|r, c| f64::from(m[c][r]));
        let world = parent * local;
        let name = node
            .name()
            .map_or_else(|| format!("node{}", node.index()), str::to_string);
        if let Some(mesh) = node.mesh() {
            let mut comp = MeshComponent {
                decomposition: Default::default(),
                offset_m: Vector3::zeros(),
                name: name.clone(),
                vertices_m: Vec::new(),
                triangles: Vec::new(),
            };
            for prim in mesh.primitives() {
                let pk = prim.index();
                let here = format!("node `{name}`, mesh {}, primitive {pk}", mesh.index());
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    return Err(format!(
                        "{here}: mode {:?} (only triangle lists are read)",
                        prim.mode()
                    ));
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(|v| &v[..]));
                let Some(pos) = reader.read_positions() else {
                    return Err(format!("{here}: no POSITION attribute"));
                };
                let base = comp.vertices_m.len() as u32;
                let mut count = 0u32;
                for p in pos {
                    let v = world.transform_point(&Point3::new(
                        f64::from(p[0]),
                        f64::from(p[1]),
                        f64::from(p[2]),
                    ));
                    comp.vertices_m.push(v);
                    count += 1;
                }
                let idx: Vec<u32> = match reader.read_indices() {
                    Some(ix) => ix.into_u32().collect(),
                    None => (0..count).collect(),
                };
                if !idx.len().is_multiple_of(3) {
                    return Err(format!(
                        "{here}: {} indices, not a multiple of 3",
                        idx.len()
                    ));
                }
                if let Some(i) = idx.iter().find(|i| **i >= count) {
                    return Err(format!("{here}: index {i} out of range ({count} vertices)"));
                }
                comp.triangles.extend(
                    idx.chunks_exact(3)
                        .map(|c| [c[0] + base, c[1] + base, c[2] + base]),
                );
            }
            // A mirroring transform turns the triangles inside out: restore the winding.
            if world.fixed_view::<3, 3>(0, 0).determinant() < 0.0 {
                for t in &mut comp.triangles {
                    t.swap(1, 2);
                }
            }
            out.push(comp);
        }
        let children: Vec<_> = node.children().collect();
        for c in children.into_iter().rev() {
            stack.push((c, world, depth + 1));
        }
    }
    Ok(out)
}

/// Mass properties of a homogeneous solid, in the frame of its vertices.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassProperties {
    /// Volume, m³.
    pub volume_m3: f64,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass, m.
    pub com_m: Vector3<f64>,
    /// Inertia tensor about the centre of mass, kg·m².
    pub inertia_kg_m2: Matrix3<f64>,
}

/// Checks that a component's triangles form a closed, consistently oriented surface (vertices
/// at the same position welded): every directed edge appears once and its reverse once. The
/// error names the first offending triangle.
pub fn check_closed(c: &MeshComponent) -> Result<(), String> {
    // Weld vertices at the same position (files repeat vertices per face, e.g. STL, OBJ with
    // normals): positions compared bit for bit.
    let mut weld: BTreeMap<[u64; 3], u32> = BTreeMap::new();
    let id: Vec<u32> = c
        .vertices_m
        .iter()
        .map(|v| {
            let key = [v.x, v.y, v.z].map(|x| (x + 0.0).to_bits());
            let n = weld.len() as u32;
            *weld.entry(key).or_insert(n)
        })
        .collect();
    let mut directed: BTreeMap<(u32, u32), (u32, usize)> = BTreeMap::new();
    for (k, t) in c.triangles.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (id[t[e] as usize], id[t[(e + 1) % 3] as usize]);
            let slot = directed.entry((a, b)).or_insert((0, k));
            slot.0 += 1;
            if slot.0 > 1 {
                return Err(format!(
                    "triangles {} and {k} run along the edge {:?}–{:?} in the same direction \
                     (not consistently oriented, or more than two triangles on an edge)",
                    slot.1,
                    c.vertices_m[t[e] as usize],
                    c.vertices_m[t[(e + 1) % 3] as usize]
                ));
            }
        }
    }
    for (&(a, b), &(_, k)) in &directed {
        if !directed.contains_key(&(b, a)) {
            return Err(format!(
                "triangle {k} has an edge no other triangle shares in the opposite direction \
                 (the mesh is open, or its orientation flips there)"
            ));
        }
    }
    Ok(())
}

/// Mass properties of the solid bounded by a closed, consistently oriented mesh of uniform
/// density (divergence theorem: a sum of signed tetrahedra from the origin). An inward-facing
/// mesh (negative volume) is taken as the same solid. Call [`check_closed`] first.
pub fn mass_properties(c: &MeshComponent, density_kg_m3: f64) -> MassProperties {
    let mut vol6 = 0.0; // 6 V
    let mut first = Vector3::zeros(); // 24 ∫ x dV
    let mut second = Matrix3::zeros(); // 120 ∫ x xᵀ dV
    for k in 0..c.triangles.len() {
        let [a, b, d] = c.corners(k).map(|p| p.coords);
        let det = a.dot(&b.cross(&d));
        vol6 += det;
        let s = a + b + d;
        first += det * s;
        second +=
            det * (a * a.transpose() + b * b.transpose() + d * d.transpose() + s * s.transpose());
    }
    let sign = if vol6 < 0.0 { -1.0 } else { 1.0 };
    let volume = sign * vol6 / 6.0;
    let mass = density_kg_m3 * volume;
    let com = first / vol6 / 4.0;
    // Second moment about the origin, ∫ρ x xᵀ dV; inertia J = tr(C) I − C, shifted to the COM.
    let c_o = second * (sign * density_kg_m3 / 120.0);
    let c_com = c_o - mass * com * com.transpose();
    let inertia = Matrix3::identity() * c_com.trace() - c_com;
    MassProperties {
        volume_m3: volume,
        mass_kg: mass,
        com_m: com,
        inertia_kg_m2: inertia,
    }
}

#[cfg(test)]
mod tests {
    //! References: the closed forms of a box's and a tetrahedron's volume, centroid and
    //! inertia; tolerances are f64 rounding (1e-12 relative).
    use super::*;

    /// A 12-triangle box with half-extents h, centred at c, outward-facing.
    fn box_mesh(h: Vector3<f64>, c: Vector3<f64>) -> MeshComponent {
        let mut v = Vec::new();
        for i in 0..8 {
            let s = Vector3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            v.push(Point3::from(c + s.component_mul(&h)));
        }
        let quads = [
            [0, 2, 3, 1], // −z
            [4, 5, 7, 6], // +z
            [0, 1, 5, 4], // −y
            [2, 6, 7, 3], // +y
            [0, 4, 6, 2], // −x
            [1, 3, 7, 5], // +x
        ];
        let mut t = Vec::new();
        for q in quads {
            t.push([q[0], q[1], q[2]]);
            t.push([q[0], q[2], q[3]]);
        }
        MeshComponent {
            decomposition: Default::default(),
            offset_m: Vector3::zeros(),
            name: "box".into(),
            vertices_m: v,
            triangles: t,
        }
    }

    #[test]
    fn box_mass_properties_match_closed_form() {
        let h = Vector3::new(0.5, 1.0, 1.5);
        let c = Vector3::new(0.3, -0.2, 2.0);
        let m = box_mesh(h, c);
        check_component(&m).expect("valid");
        check_closed(&m).expect("closed");
        let rho = 2700.0;
        let p = mass_properties(&m, rho);
        let (a, b, d) = (2.0 * h.x, 2.0 * h.y, 2.0 * h.z);
        let mass = rho * a * b * d;
        assert!((p.volume_m3 - a * b * d).abs() < 1e-12 * a * b * d);
        assert!((p.mass_kg - mass).abs() < 1e-12 * mass);
        assert!((p.com_m - c).norm() < 1e-12);
        let want = Matrix3::from_diagonal(&Vector3::new(
            mass * (b * b + d * d) / 12.0,
            mass * (a * a + d * d) / 12.0,
            mass * (a * a + b * b) / 12.0,
        ));
        assert!(
            (p.inertia_kg_m2 - want).norm() < 1e-9 * want.norm(),
            "{}",
            p.inertia_kg_m2
        );
    }

    #[test]
    fn tetrahedron_mass_properties_match_closed_form() {
        // Corner tetrahedron (0, a e1, b e2, c e3): V = abc/6, centroid (a, b, c)/4, and
        // about the origin ∫x² dm = m a²/10, ∫xy dm = m a b/20 (Tonon 2004).
        let (a, b, c) = (1.0, 2.0, 3.0);
        let v = vec![
            Point3::origin(),
            Point3::new(a, 0.0, 0.0),
            Point3::new(0.0, b, 0.0),
            Point3::new(0.0, 0.0, c),
        ];
        let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let m = MeshComponent {
            decomposition: Default::default(),
            offset_m: Vector3::zeros(),
            name: "tet".into(),
            vertices_m: v,
            triangles: t,
        };
        check_closed(&m).expect("closed");
        let rho = 1000.0;
        let p = mass_properties(&m, rho);
        let vol = a * b * c / 6.0;
        let mass = rho * vol;
        assert!((p.volume_m3 - vol).abs() < 1e-12);
        let com = Vector3::new(a, b, c) / 4.0;
        assert!((p.com_m - com).norm() < 1e-12);
        let s = Matrix3::new(
            a * a / 10.0,
            a * b / 20.0,
            a * c / 20.0,
            a * b / 20.0,
            b * b / 10.0,
            b * c / 20.0,
            a * c / 20.0,
            b * c / 20.0,
            c * c / 10.0,
        ) * mass;
        let s_com = s - mass * com * com.transpose();
        let want = Matrix3::identity() * s_com.trace() - s_com;
        assert!((p.inertia_kg_m2 - want).norm() < 1e-9 * want.norm());
        // Inside out: the same solid.
        let mut inv = m.clone();
        for t in &mut inv.triangles {
            t.swap(1, 2);
        }
        let q = mass_properties(&inv, rho);
        assert!((q.mass_kg - mass).abs() < 1e-9 && (q.com_m - com).norm() < 1e-12);
    }

    #[test]
    fn open_or_flipped_meshes_are_not_closed() {
        let mut m = box_mesh(Vector3::repeat(1.0), Vector3::zeros());
        m.triangles.pop();
        assert!(check_closed(&m).is_err());
        let mut f = box_mesh(Vector3::repeat(1.0), Vector3::zeros());
        f.triangles[0].swap(1, 2);
        assert!(check_closed(&f).is_err());
    }

    #[test]
    fn degenerate_and_bad_triangles_are_refused() {
        let mut m = box_mesh(Vector3::repeat(1.0), Vector3::zeros());
        m.triangles.push([0, 0, 1]);
        let e = check_component(&m).expect_err("degenerate");
        assert!(e.contains("triangle 12") && e.contains("degenerate"), "{e}");
        let mut n = box_mesh(Vector3::repeat(1.0), Vector3::zeros());
        n.vertices_m[3].x = f64::NAN;
        assert!(check_component(&n).expect_err("nan").contains("vertex 3"));
        let mut o = box_mesh(Vector3::repeat(1.0), Vector3::zeros());
        o.triangles.push([0, 1, 99]);
        assert!(
            check_component(&o)
                .expect_err("range")
                .contains("vertex 99")
        );
    }
}
