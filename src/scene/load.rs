//! Loading a scene: RON parsing, `--set path=value` overrides applied to the text (so every
//! error still points at a line and column), and validation errors located in the file.
//!
//! Paths name fields with dots and list elements by index or by their `name`:
//! `bodies.chaser.initial.pos_m.0`, `bodies[1].mass_kg`, `environment.reference.e`.

use super::Scene;
use std::fmt;
use std::path::Path;

/// A scene that could not be loaded: where, which field, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// File (or `<string>` / `--set`).
    pub file: String,
    /// 1-based line, 0 when unknown.
    pub line: usize,
    /// 1-based column, 0 when unknown.
    pub col: usize,
    /// The field path, e.g. `bodies.chaser.mass_kg` (empty for syntax errors).
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if self.line > 0 {
            write!(f, ":{}:{}", self.line, self.col)?;
        }
        if !self.field.is_empty() {
            write!(f, ": field `{}`", self.field)?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for SceneError {}

/// Largest scene or trials file read, bytes (16 MiB). Larger files are refused before they are
/// read whole, so a hostile file (or `/dev/zero`) cannot exhaust memory.
pub const MAX_FILE_BYTES: usize = 16 << 20;

/// Deepest bracket nesting accepted in a scene, a trials file or a `--set` value. The deepest
/// bundled scene nests 7 levels; the check runs before any parser so that no input can overflow
/// the stack.
pub const MAX_NESTING: usize = 64;

/// Most `--set` overrides in one command, and the longest one, bytes.
pub const MAX_OVERRIDES: usize = 1024;
/// Longest `--set` assignment, bytes.
pub const MAX_OVERRIDE_BYTES: usize = 64 << 10;

/// One `--set` applied to the text: bytes `at .. at + new_len` of the text after it replaced
/// `old_len` bytes of the text before it.
#[derive(Debug, Clone)]
struct Edit {
    at: usize,
    old_len: usize,
    new_len: usize,
    /// Offset of the value inside the inserted bytes (non-zero when `path: value, ` was
    /// inserted).
    value_at: usize,
    /// The assignment as the user wrote it.
    assignment: String,
    /// Byte offset of the value inside `assignment`.
    value_in_assignment: usize,
}

/// A parsed, validated scene with the text it came from (after overrides), so that checks made
/// later (e.g. geometry overlaps) can still point at a line and column.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    /// The scene.
    pub scene: Scene,
    /// Its text, overrides applied.
    pub text: String,
    /// The file name used in errors.
    pub file: String,
    /// The overrides applied, in order, for mapping positions back to what the user wrote.
    edits: Vec<Edit>,
    /// The file's text before the overrides.
    original: String,
}

/// Where a byte of the rewritten text came from: the file (line and column as the user sees
/// them, unshifted by overrides; `original` is the file's text) or a `--set` argument (line
/// and column inside it).
fn position(original: &str, file: &str, edits: &[Edit], offset: usize) -> (String, usize, usize) {
    let mut o = offset;
    for e in edits.iter().rev() {
        if o < e.at {
            continue;
        }
        if o >= e.at + e.new_len {
            o = o - e.new_len + e.old_len;
            continue;
        }
        let within = o - e.at;
        let idx = if within < e.value_at {
            0
        } else {
            (e.value_in_assignment + within - e.value_at).min(e.assignment.len())
        };
        let (line, col) = line_col(&e.assignment, idx);
        return (override_file(file, &e.assignment), line, col);
    }
    let (line, col) = line_col(original, o);
    (file.to_string(), line, col)
}

/// The name errors inside a `--set` argument carry: `FILE (--set ASSIGNMENT)`, control
/// characters escaped so that the message stays on one line.
fn override_file(file: &str, assignment: &str) -> String {
    format!("{file} (--set {})", assignment.escape_debug())
}

impl LoadedScene {
    /// SHA-256 of the scene text as read (before the overrides), hex.
    pub fn source_sha256(&self) -> String {
        crate::report::sha256_hex(self.original.as_bytes())
    }

    /// The `--set` overrides applied, in order, as written.
    pub fn overrides(&self) -> Vec<String> {
        self.edits.iter().map(|e| e.assignment.clone()).collect()
    }

    /// Provenance of the scene: its file, its SHA-256 and every `--set` applied, with the rpod
    /// version and git commit that loaded it.
    pub fn provenance(&self) -> serde_json::Value {
        let mut v = crate::report::build_provenance();
        v["scene_file"] = serde_json::json!(self.file);
        v["scene_sha256"] = serde_json::json!(self.source_sha256());
        v["set"] = serde_json::json!(self.overrides());
        v
    }

    /// An error about the field at `path`, located in the text (or in the `--set` argument
    /// that wrote the value).
    pub fn error_at(&self, path: &str, message: impl Into<String>) -> SceneError {
        let (file, line, col) = match locate(&self.text, path) {
            Some((s, _)) => position(&self.original, &self.file, &self.edits, s),
            None => (self.file.clone(), 0, 0),
        };
        SceneError {
            file,
            line,
            col,
            field: path.to_string(),
            message: message.into(),
        }
    }
}

fn whole_file_error(file: &str, message: String) -> SceneError {
    SceneError {
        file: file.to_string(),
        line: 0,
        col: 0,
        field: String::new(),
        message,
    }
}

/// Reads a text file for the loaders: at most [`MAX_FILE_BYTES`], UTF-8 (an invalid byte is
/// reported at its line and column). `what` names the file in messages ("scene", "trials file").
pub fn read_text(path: &Path, what: &str) -> Result<String, SceneError> {
    use std::io::Read;
    let file = path.display().to_string();
    // A FIFO, socket or device is refused before anything is read (no hang, no endless read).
    // (The error is reported after the file's name: the path is not repeated in the message.)
    let f = crate::report::fsio::open_regular(path, what)
        .map_err(|e| whole_file_error(&file, e.to_string().replacen(&format!(" {file}"), "", 1)))?;
    let mut bytes = Vec::new();
    f.take(MAX_FILE_BYTES as u64 + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| whole_file_error(&file, format!("cannot read the {what}: {e}")))?;
    if bytes.len() > MAX_FILE_BYTES {
        return Err(whole_file_error(
            &file,
            format!(
                "the {what} is larger than {} MiB (the limit for a scene or trials file)",
                MAX_FILE_BYTES >> 20
            ),
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let prefix = std::str::from_utf8(&bytes[..valid]).unwrap_or("");
        let (line, col) = line_col(prefix, valid);
        SceneError {
            file: file.clone(),
            line,
            col,
            field: String::new(),
            message: format!(
                "byte 0x{:02X} is not valid UTF-8 (scene and trials files are UTF-8 text)",
                bytes[valid]
            ),
        }
    })
}

/// Reads, overrides, parses and validates a scene file.
pub fn load_scene_file(path: &Path, overrides: &[String]) -> Result<LoadedScene, SceneError> {
    let text = read_text(path, "scene")?;
    load_scene_str(&text, &path.display().to_string(), overrides)
}

/// Parses and validates scene text; `file` names it in errors.
pub fn load_scene_str(
    text: &str,
    file: &str,
    overrides: &[String],
) -> Result<LoadedScene, SceneError> {
    if text.len() > MAX_FILE_BYTES {
        return Err(whole_file_error(
            file,
            format!("the scene is larger than {} MiB", MAX_FILE_BYTES >> 20),
        ));
    }
    if overrides.len() > MAX_OVERRIDES {
        return Err(whole_file_error(
            file,
            format!(
                "at most {MAX_OVERRIDES} --set overrides, got {}",
                overrides.len()
            ),
        ));
    }
    check_nesting(text, file)?;
    let original = text.to_string();
    let mut text = text.to_string();
    let mut edits = Vec::with_capacity(overrides.len());
    for o in overrides {
        let (t, e) = apply_override_edit(&text, file, o)?;
        text = t;
        edits.push(e);
    }
    if text.len() > MAX_FILE_BYTES {
        return Err(whole_file_error(
            file,
            format!(
                "the scene with its --set overrides is larger than {} MiB",
                MAX_FILE_BYTES >> 20
            ),
        ));
    }
    let scene: Scene = parse_ron_mapped(&text, file, &original, &edits)?;
    let loaded = LoadedScene {
        scene,
        text,
        file: file.to_string(),
        edits,
        original,
    };
    if let Err((path, message)) = super::validate::validate(&loaded.scene) {
        return Err(loaded.error_at(&path, message));
    }
    let mut loaded = loaded;
    if resolve_meshes(&mut loaded)? {
        // Mass properties computed from meshes are held to the same limits as stated ones.
        if let Err((path, message)) = super::validate::validate(&loaded.scene) {
            return Err(loaded.error_at(&path, message));
        }
    }
    Ok(loaded)
}

/// Reads every `Mesh` shape's file (relative to the scene file's folder) into the scene, and
/// fills the mass properties of the bodies that take them from their meshes. Returns whether
/// any body's mass properties were computed. Errors point at the shape's `path` (or the mass
/// field) and name the mesh file and the element.
fn resolve_meshes(loaded: &mut LoadedScene) -> Result<bool, SceneError> {
    use super::{PartSpec, ShapeSpec};
    use crate::geometry::mesh;
    let base = Path::new(&loaded.file)
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let mut scene = std::mem::take(&mut loaded.scene.bodies);
    let mut computed = false;
    let result = (|| {
        for b in &mut scene {
            let bp = format!("bodies.{}", b.name);
            let mut mass_sources: Vec<(String, mesh::MassProperties, nalgebra::Isometry3<f64>)> =
                Vec::new();
            for part in &mut b.parts {
                let pp = format!("{bp}.parts.{}", part.name());
                let (PartSpec::Bus {
                    shape,
                    pos_m,
                    attitude,
                    ..
                }
                | PartSpec::Antenna {
                    shape,
                    pos_m,
                    attitude,
                    ..
                }) = part
                else {
                    continue;
                };
                let pose = nalgebra::Isometry3::from_parts(
                    nalgebra::Translation3::from(nalgebra::Vector3::from(*pos_m)),
                    attitude.to_quat(),
                );
                let ShapeSpec::Mesh {
                    path,
                    scale,
                    nodes,
                    max_triangles,
                    density_kg_m3,
                    loaded: data,
                    ..
                } = shape
                else {
                    continue;
                };
                let file = base.join(path.as_str());
                let m = mesh::load_mesh_file(&file, *scale, nodes, *max_triangles)
                    .map_err(|e| loaded.error_at(&format!("{pp}.shape.path"), e))?;
                if let Some(rho) = density_kg_m3 {
                    if !b.mass_from_meshes {
                        return Err(loaded.error_at(
                            &format!("{pp}.shape.density_kg_m3"),
                            "the body does not take its mass from its meshes \
                             (set mass_from_meshes: true, or leave the density out)",
                        ));
                    }
                    for c in &m.components {
                        mesh::check_closed(c).map_err(|e| {
                            loaded.error_at(
                                &format!("{pp}.shape.density_kg_m3"),
                                format!(
                                    "{}: component `{}` cannot be a mass source: {e}; a mesh \
                                     that is not closed can still be a collision shape \
                                     (leave density_kg_m3 out)",
                                    file.display(),
                                    c.name
                                ),
                            )
                        })?;
                        mass_sources.push((
                            c.name.clone(),
                            mesh::mass_properties(c, *rho),
                            pose * nalgebra::Translation3::from(c.offset_m),
                        ));
                    }
                }
                *data = Some(std::sync::Arc::new(m));
            }
            // Component names become collider names: unique on the body.
            let cols = super::parts::expand_body(b);
            for (k, c) in cols.iter().enumerate() {
                if cols[..k].iter().any(|o| o.name == c.name) {
                    return Err(loaded.error_at(
                        &format!("{bp}.parts.{}", c.part),
                        format!(
                            "collider `{}` is named twice on the body (mesh components are \
                             named by their glTF node or OBJ object; select them with `nodes`)",
                            c.name
                        ),
                    ));
                }
            }
            if b.mass_from_meshes {
                if !b.mass_kg.is_nan() || !b.inertia_kg_m2.xx.is_nan() {
                    let f = if b.mass_kg.is_nan() {
                        "inertia_kg_m2"
                    } else {
                        "mass_kg"
                    };
                    return Err(loaded.error_at(
                        &format!("{bp}.{f}"),
                        "leave it out: mass_from_meshes computes the mass properties",
                    ));
                }
                if mass_sources.is_empty() {
                    return Err(loaded.error_at(
                        &format!("{bp}.mass_from_meshes"),
                        "no part of the body is a Mesh with a density_kg_m3",
                    ));
                }
                let total = combine_mass(&mass_sources);
                b.mass_kg = total.mass_kg;
                b.com_m = [total.com_m.x, total.com_m.y, total.com_m.z];
                let j = total.inertia_kg_m2;
                b.inertia_kg_m2 = super::InertiaSpec {
                    xx: j[(0, 0)],
                    yy: j[(1, 1)],
                    zz: j[(2, 2)],
                    xy: j[(0, 1)],
                    xz: j[(0, 2)],
                    yz: j[(1, 2)],
                };
                computed = true;
            }
        }
        Ok(())
    })();
    loaded.scene.bodies = scene;
    result.map(|()| computed)
}

/// Mass properties of several solids, each given in its part frame with the part's pose in
/// the body frame: total mass, centre of mass, and the inertia about it (parallel axes).
pub fn combine_mass(
    parts: &[(
        String,
        crate::geometry::mesh::MassProperties,
        nalgebra::Isometry3<f64>,
    )],
) -> crate::geometry::mesh::MassProperties {
    use nalgebra::{Matrix3, Vector3};
    let mass: f64 = parts.iter().map(|p| p.1.mass_kg).sum();
    let volume: f64 = parts.iter().map(|p| p.1.volume_m3).sum();
    let com = parts
        .iter()
        .map(|(_, m, pose)| (pose * nalgebra::Point3::from(m.com_m)).coords * m.mass_kg)
        .sum::<Vector3<f64>>()
        / mass;
    let mut j = Matrix3::zeros();
    for (_, m, pose) in parts {
        let r = pose.rotation.to_rotation_matrix().into_inner();
        let c = (pose * nalgebra::Point3::from(m.com_m)).coords - com;
        j += r * m.inertia_kg_m2 * r.transpose()
            + m.mass_kg * (Matrix3::identity() * c.norm_squared() - c * c.transpose());
    }
    crate::geometry::mesh::MassProperties {
        volume_m3: volume,
        mass_kg: mass,
        com_m: com,
        inertia_kg_m2: j,
    }
}

/// Refuses text whose brackets nest deeper than [`MAX_NESTING`], pointing at the first bracket
/// too deep. Strings, character literals and comments are skipped; unbalanced brackets are
/// left to the parser to report.
pub fn check_nesting(text: &str, file: &str) -> Result<(), SceneError> {
    let b = text.as_bytes();
    let mut depth = 0usize;
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'(' | b'[' | b'{' => {
                depth += 1;
                if depth > MAX_NESTING {
                    let (line, col) = line_col(text, i);
                    return Err(SceneError {
                        file: file.to_string(),
                        line,
                        col,
                        field: String::new(),
                        message: format!(
                            "brackets nested deeper than {MAX_NESTING} levels (the limit)"
                        ),
                    });
                }
                i += 1;
            }
            b')' | b']' | b'}' => {
                depth = depth.saturating_sub(1);
                i += 1;
            }
            _ => i = skip_token(b, i),
        }
    }
    Ok(())
}

/// From `i`, skips one comment, string, raw string or character literal (returning the index
/// after it, at most `b.len()`), or one other byte.
fn skip_token(b: &[u8], i: usize) -> usize {
    let at = |k: usize| b.get(k).copied();
    match b[i] {
        b'/' if at(i + 1) == Some(b'/') => {
            let mut j = i + 2;
            while j < b.len() && b[j] != b'\n' {
                j += 1;
            }
            j
        }
        b'/' if at(i + 1) == Some(b'*') => {
            let mut depth = 1usize;
            let mut j = i + 2;
            while j < b.len() && depth > 0 {
                if b[j] == b'/' && at(j + 1) == Some(b'*') {
                    depth += 1;
                    j += 2;
                } else if b[j] == b'*' && at(j + 1) == Some(b'/') {
                    depth -= 1;
                    j += 2;
                } else {
                    j += 1;
                }
            }
            j.min(b.len())
        }
        q @ (b'"' | b'\'') => {
            let mut j = i + 1;
            while j < b.len() && b[j] != q {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            (j + 1).min(b.len())
        }
        b'r' if (i == 0 || !is_ident_byte(b[i - 1]))
            && matches!(at(i + 1), Some(b'"') | Some(b'#')) =>
        {
            // Raw string r#"…"#: count the hashes, find `"` followed by as many.
            let mut j = i + 1;
            let mut hashes = 0;
            while at(j) == Some(b'#') {
                hashes += 1;
                j += 1;
            }
            if at(j) != Some(b'"') {
                return i + 1;
            }
            j += 1;
            while j < b.len() {
                if b[j] == b'"' && (1..=hashes).all(|h| at(j + h) == Some(b'#')) {
                    return (j + 1 + hashes).min(b.len());
                }
                j += 1;
            }
            b.len()
        }
        _ => i + 1,
    }
}

fn is_ident_byte(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// Parses any RON document (e.g. a trials file), with serde errors located like scene errors.
/// Optional fields may be written bare (`duration_s: 30.0`) or as `Some(30.0)`. Nesting is
/// limited to [`MAX_NESTING`] before parsing.
pub fn parse_ron<T: serde::de::DeserializeOwned>(text: &str, file: &str) -> Result<T, SceneError> {
    check_nesting(text, file)?;
    parse_ron_mapped(text, file, text, &[])
}

fn parse_ron_mapped<T: serde::de::DeserializeOwned>(
    text: &str,
    file: &str,
    original: &str,
    edits: &[Edit],
) -> Result<T, SceneError> {
    let mut ignored: Vec<Vec<String>> = Vec::new();
    let value = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str_seed(
            text,
            RefuseIgnored::<T>(&mut ignored, std::marker::PhantomData),
        )
        .map_err(|e| {
            let offset = offset_of(text, e.span.start.line, e.span.start.col);
            let (file, line, col) = if e.span.start.line == 0 {
                (file.to_string(), 0, 0)
            } else {
                position(original, file, edits, offset)
            };
            SceneError {
                file,
                line,
                col,
                field: field_at_offset(text, offset),
                message: e.code.to_string(),
            }
        })?;
    if let Ok(root) = parse_tree(text) {
        let mut bad = None;
        check_numbers(text, &root, "", &mut Vec::new(), &mut bad);
        if let Some((offset, field, message)) = bad {
            let (file, line, col) = position(original, file, edits, offset);
            return Err(SceneError {
                file,
                line,
                col,
                field,
                message,
            });
        }
    }
    // A field no type consumed: every struct and variant refuses unknown fields, at any depth
    // (law and Sequencer params, contact laws, `--set` included), whatever its serde attributes.
    if let Some(path) = ignored.first() {
        let joined = path.join(".");
        let offset = locate(text, &joined).map_or(0, |(s, _)| s);
        let (file, line, col) = position(original, file, edits, offset);
        let name = path.last().map_or("", String::as_str);
        return Err(SceneError {
            file,
            line,
            col,
            field: joined.clone(),
            message: format!(
                "unknown field `{}` here: it is not a field of this struct or variant, so it \
                 would be silently ignored; check its spelling against the scene format",
                name.escape_debug()
            ),
        });
    }
    Ok(value)
}

/// Largest magnitude of any number in a scene or trials file. Far beyond any physical parameter
/// rpod models, and small enough that the norm of a 3-vector and the product of two numbers stay
/// finite in f64 (1e100² = 1e200): a direction can never normalise to zero or NaN by overflow.
pub const MAX_NUMBER: f64 = 1e100;

/// The limit on a number by the unit its field name ends with (`…_m_s`, `…_rad_s`, `…_n`):
/// (unit, largest magnitude, what it is). Units not listed (compound ones such as `_n_s_m`, and
/// unitless gains) get [`MAX_NUMBER`] only; bounds that depend on meaning (positive, below one)
/// stay with each type's own validation.
const UNIT_LIMITS: &[(&str, f64, &str)] = &[
    ("_m_s2", 1e6, "an acceleration (m/s²)"),
    ("_m_s", super::validate::MAX_SPEED_M_S, "a speed (m/s)"),
    (
        "_rad_s",
        super::validate::MAX_RATE_DEG_S * std::f64::consts::PI / 180.0,
        "a rate (rad/s)",
    ),
    ("_deg_s", super::validate::MAX_RATE_DEG_S, "a rate (°/s)"),
    ("_nm", super::validate::MAX_FORCE_N, "a torque (N·m)"),
    ("_n", super::validate::MAX_FORCE_N, "a force (N)"),
    ("_m", super::validate::MAX_ORBIT_RADIUS_M, "a length (m)"),
];

/// The unit a field name ends with: its longest trailing run of unit tokens (`vel_m_s` → `m_s`,
/// `viscous_drag_n_s_m` → `n_s_m`, `stiffness_n_m1_5` → `n_m1_5`, `damping_ratio` → ``).
fn unit_of(key: &str) -> String {
    const TOKENS: &[&str] = &[
        "m", "s", "s2", "n", "nm", "rad", "deg", "kg", "m1", "m2", "m3", "5", "hz",
    ];
    let parts: Vec<&str> = key.split('_').collect();
    let mut k = parts.len();
    // The first part is the quantity's name even when it looks like a unit (`s`, `m`).
    while k > 1 && TOKENS.contains(&parts[k - 1]) {
        k -= 1;
    }
    parts[k..].join("_")
}

/// Checks every number of the text, wherever it appears (law and Sequencer params, sensors,
/// actuators, contact laws, guarantees, trials grids): finite, at most [`MAX_NUMBER`] in
/// magnitude, and within the limit of its unit ([`UNIT_LIMITS`], from the field name; the
/// elements of a tuple take their field's unit). One shared pass, so no type can forget it.
/// Records the first failure as (byte offset, field path, message).
fn check_numbers(
    text: &str,
    node: &Node,
    key: &str,
    path: &mut Vec<String>,
    bad: &mut Option<(usize, String, String)>,
) {
    if bad.is_some() {
        return;
    }
    match &node.kind {
        NodeKind::Struct { fields, .. } => {
            for (k, _, v) in fields {
                path.push(k.clone());
                check_numbers(text, v, k, path, bad);
                path.pop();
            }
        }
        NodeKind::Seq(items) => {
            for (i, v) in items.iter().enumerate() {
                // Paths as the other scene errors spell them: a named element by its name, a
                // vector's component by its field alone.
                // A newtype (`Some((…))`, `AirBearing((…))`) is transparent, as in [`locate`];
                // a one-element list `[X(…)]` is not (its element keeps its label).
                let list = text.as_bytes().get(node.start) == Some(&b'[');
                let newtype =
                    !list && items.len() == 1 && matches!(v.kind, NodeKind::Struct { .. });
                if newtype || matches!(v.kind, NodeKind::Atom) {
                    check_numbers(text, v, key, path, bad);
                    continue;
                }
                path.push(element_label(text, v).unwrap_or_else(|| i.to_string()));
                check_numbers(text, v, key, path, bad);
                path.pop();
            }
        }
        NodeKind::Atom => {
            let raw = text.get(node.start..node.end.min(text.len())).unwrap_or("");
            let raw = raw.trim();
            // Only numbers: names, strings, variants and booleans are other atoms.
            let starts_numeric = raw
                .trim_start_matches(['+', '-'])
                .starts_with(|c: char| c.is_ascii_digit() || c == '.' || c == 'i' || c == 'N');
            if !starts_numeric || raw.starts_with('"') {
                return;
            }
            let Ok(x) = raw.replace('_', "").parse::<f64>() else {
                return;
            };
            let unit_of_key = unit_of(key);
            let unit = UNIT_LIMITS
                .iter()
                .find(|(u, _, _)| u.trim_start_matches('_') == unit_of_key);
            let why = if !x.is_finite() {
                Some(format!("{raw} is not a finite number"))
            } else if let Some((u, max, what)) = unit
                && x.abs() > *max
            {
                Some(format!(
                    "{raw} is beyond ±{max:e}, the largest value of {what} a scene may hold \
                     (field unit `{}`); it would change the model's meaning or disable it",
                    u.trim_start_matches('_')
                ))
            } else if x.abs() > MAX_NUMBER {
                Some(format!(
                    "{raw} is beyond ±{MAX_NUMBER:e}, the largest number a scene may hold (so \
                     that no norm or product overflows)"
                ))
            } else {
                None
            };
            if let Some(why) = why {
                *bad = Some((node.start, path.join("."), why));
            }
        }
    }
}

/// Deserialises a `T` and records the path of every field the types did not consume.
struct RefuseIgnored<'a, T>(&'a mut Vec<Vec<String>>, std::marker::PhantomData<T>);

impl<'de, T: serde::de::DeserializeOwned> serde::de::DeserializeSeed<'de> for RefuseIgnored<'_, T> {
    type Value = T;
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<T, D::Error> {
        let sink = self.0;
        serde_ignored::deserialize(d, |path| {
            if sink.len() < 16 {
                let mut segs = Vec::new();
                ignored_segments(&path, &mut segs);
                sink.push(segs);
            }
        })
    }
}

/// The path of an ignored field as the segments [`locate`] walks (field names and indices).
fn ignored_segments(p: &serde_ignored::Path<'_>, out: &mut Vec<String>) {
    use serde_ignored::Path;
    match p {
        Path::Root => {}
        Path::Seq { parent, index } => {
            ignored_segments(parent, out);
            out.push(index.to_string());
        }
        Path::Map { parent, key } => {
            ignored_segments(parent, out);
            out.push(key.clone());
        }
        Path::Some { parent }
        | Path::NewtypeStruct { parent }
        | Path::NewtypeVariant { parent } => ignored_segments(parent, out),
    }
}

/// Applies one `path=value` override to scene text. The value is one RON value (`3.5`, `true`,
/// `(1.0, 2.0, 3.0)`, `"name"`), without comments. A field absent from the text is inserted
/// into its struct.
pub fn apply_override(text: &str, file: &str, assignment: &str) -> Result<String, SceneError> {
    apply_override_edit(text, file, assignment).map(|(t, _)| t)
}

fn apply_override_edit(
    text: &str,
    file: &str,
    assignment: &str,
) -> Result<(String, Edit), SceneError> {
    let path_part = assignment.split('=').next().unwrap_or("").trim();
    let err_at = |line: usize, col: usize, message: String| SceneError {
        file: override_file(file, assignment),
        line,
        col,
        field: path_part.to_string(),
        message,
    };
    let err = |col: usize, message: String| err_at(usize::from(col > 0), col, message);
    if assignment.len() > MAX_OVERRIDE_BYTES {
        return Err(err(
            0,
            format!("a --set is at most {} KiB", MAX_OVERRIDE_BYTES >> 10),
        ));
    }
    let Some(eq) = assignment.find('=') else {
        return Err(err(1, "expected `path=value`".into()));
    };
    let (path, raw_value) = (assignment[..eq].trim(), &assignment[eq + 1..]);
    let value = raw_value.trim();
    let value_in_assignment = eq + 1 + (raw_value.len() - raw_value.trim_start().len());
    if path.is_empty() || value.is_empty() {
        return Err(err(1, "expected `path=value`".into()));
    }
    check_value(value).map_err(|(k, m)| {
        let (line, col) = line_col(assignment, value_in_assignment + k);
        err_at(line, col, m)
    })?;
    let root = parse_tree(text).map_err(|m| err(0, format!("cannot read the scene text: {m}")))?;
    let segs = split_path(path);
    // Navigate to the parent; the last segment may be missing (then insert it).
    let mut node = &root;
    for (i, seg) in segs.iter().enumerate() {
        let last = i + 1 == segs.len();
        let seg_col = assignment.find(seg.as_str()).map_or(1, |k| k + 1);
        match child(text, node, seg) {
            Some(c) => {
                if last {
                    let mut out = String::with_capacity(text.len() + value.len());
                    out.push_str(&text[..c.start]);
                    out.push_str(value);
                    out.push_str(&text[c.end..]);
                    let edit = Edit {
                        at: c.start,
                        old_len: c.end - c.start,
                        new_len: value.len(),
                        value_at: 0,
                        assignment: assignment.to_string(),
                        value_in_assignment,
                    };
                    return Ok((out, edit));
                }
                node = c;
            }
            None => {
                if last
                    && let NodeKind::Struct { open, .. } = &unwrap_newtype(node).kind
                    && is_identifier(seg)
                {
                    let inserted = format!("{seg}: {value}, ");
                    let mut out = String::with_capacity(text.len() + inserted.len());
                    out.push_str(&text[..open + 1]);
                    out.push_str(&inserted);
                    out.push_str(&text[open + 1..]);
                    let edit = Edit {
                        at: open + 1,
                        old_len: 0,
                        new_len: inserted.len(),
                        value_at: seg.len() + 2,
                        assignment: assignment.to_string(),
                        value_in_assignment,
                    };
                    return Ok((out, edit));
                }
                return Err(err(
                    seg_col,
                    format!("no field `{seg}` at `{}`", segs[..i].join(".")),
                ));
            }
        }
    }
    Err(err(1, "empty path".into()))
}

/// A field name that may be inserted into a struct: `[A-Za-z_][A-Za-z0-9_]*`.
fn is_identifier(s: &str) -> bool {
    let mut c = s.bytes();
    matches!(c.next(), Some(b) if b.is_ascii_alphabetic() || b == b'_') && c.all(is_ident_byte)
}

/// A `--set` value must be exactly one RON value, nested at most [`MAX_NESTING`] deep, without
/// comments (which would comment out the scene text after it). On failure: the byte offset in
/// the value and why.
fn check_value(value: &str) -> Result<(), (usize, String)> {
    check_nesting(value, "").map_err(|e| {
        (
            offset_of(value, e.line, e.col),
            format!("the value's brackets nest deeper than {MAX_NESTING} levels"),
        )
    })?;
    let b = value.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'/' && matches!(b.get(i + 1), Some(b'/') | Some(b'*')) {
            return Err((i, "a --set value cannot contain a comment".into()));
        }
        i = skip_token(b, i);
    }
    let mut lx = Lexer { b, i: 0 };
    let node = parse_value(&mut lx, 0).map_err(|m| (lx.i.min(b.len()), m))?;
    lx.skip_ws();
    if lx.i < b.len() || node.end > b.len() {
        return Err((
            lx.i.min(b.len()),
            "expected one value (text follows the value)".into(),
        ));
    }
    Ok(())
}

/// Splits `a.b[2].c` into `["a", "b", "2", "c"]`.
pub fn split_path(path: &str) -> Vec<String> {
    path.replace('[', ".")
        .replace(']', "")
        .split('.')
        .filter(|s| !s.is_empty())
        .map(str::to_string)
        .collect()
}

/// Byte span of the value at `path` in RON text.
pub fn locate(text: &str, path: &str) -> Option<(usize, usize)> {
    let root = parse_tree(text).ok()?;
    let mut node = &root;
    let mut best = (root.start, root.end);
    for seg in split_path(path) {
        match child(text, node, &seg) {
            Some(c) => {
                node = c;
                best = (c.start, c.end);
            }
            None => break,
        }
    }
    Some(best)
}

/// 1-based line and column of a byte offset.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let before = &text[..end];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Byte offset of a 1-based (line, column) in `text` (columns count characters); the end of
/// the text when past it.
fn offset_of(text: &str, line: usize, col: usize) -> usize {
    let mut l = 1;
    let mut line_start = if line <= 1 { Some(0) } else { None };
    if line_start.is_none() {
        for (i, ch) in text.char_indices() {
            if ch == '\n' {
                l += 1;
                if l == line {
                    line_start = Some(i + 1);
                    break;
                }
            }
        }
    }
    let Some(start) = line_start else {
        return text.len();
    };
    for (c, (j, ch)) in (1..).zip(text[start..].char_indices()) {
        if c == col || ch == '\n' {
            return start + j;
        }
    }
    text.len()
}

/// The innermost field path that contains a byte offset (for serde errors).
fn field_at_offset(text: &str, offset: usize) -> String {
    let Ok(root) = parse_tree(text) else {
        return String::new();
    };
    let mut path = Vec::new();
    descend(text, &root, offset, &mut path);
    path.join(".")
}

fn descend(text: &str, node: &Node, offset: usize, path: &mut Vec<String>) {
    match &node.kind {
        NodeKind::Struct { fields, .. } => {
            for (key, key_start, v) in fields {
                if offset >= *key_start && offset <= v.end {
                    path.push(key.clone());
                    descend(text, v, offset, path);
                    return;
                }
            }
        }
        NodeKind::Seq(items) => {
            for (i, v) in items.iter().enumerate() {
                if offset >= v.start && offset <= v.end {
                    path.push(element_label(text, v).unwrap_or_else(|| i.to_string()));
                    descend(text, v, offset, path);
                    return;
                }
            }
        }
        NodeKind::Atom => {}
    }
}

/// A list element is labelled by its `name` field when it has one.
fn element_label(text: &str, v: &Node) -> Option<String> {
    if let NodeKind::Struct { fields, .. } = &v.kind {
        for (k, _, val) in fields {
            if k == "name" {
                return Some(text[val.start..val.end].trim_matches('"').to_string());
            }
        }
    }
    None
}

/// The struct inside a newtype such as `Some((…))`, or the node itself.
fn unwrap_newtype(node: &Node) -> &Node {
    match &node.kind {
        NodeKind::Seq(items) => match items.as_slice() {
            [only] if matches!(only.kind, NodeKind::Struct { .. }) => only,
            _ => node,
        },
        _ => node,
    }
}

fn child<'a>(text: &str, node: &'a Node, seg: &str) -> Option<&'a Node> {
    match &node.kind {
        NodeKind::Struct { fields, .. } => fields.iter().find(|(k, _, _)| k == seg).map(|f| &f.2),
        NodeKind::Seq(items) => {
            if let Ok(i) = seg.parse::<usize>() {
                items.get(i)
            } else if let Some(v) = items
                .iter()
                .find(|v| element_label(text, v).as_deref() == Some(seg))
            {
                Some(v)
            } else if let [only] = items.as_slice()
                && matches!(only.kind, NodeKind::Struct { .. })
            {
                // A newtype such as `Some((…))`: its fields are the inner struct's.
                child(text, only, seg)
            } else {
                None
            }
        }
        NodeKind::Atom => None,
    }
}

/// A RON value's span and structure (just enough to find fields).
#[derive(Debug)]
struct Node {
    start: usize,
    end: usize,
    kind: NodeKind,
}

#[derive(Debug)]
enum NodeKind {
    /// `Name(k: v, …)` or `(k: v, …)`; `open` is the byte index of `(`.
    Struct {
        open: usize,
        fields: Vec<(String, usize, Node)>,
    },
    /// `[a, b]`, `(a, b)` or `Name(a, b)`.
    Seq(Vec<Node>),
    /// Anything else.
    Atom,
}

struct Lexer<'a> {
    b: &'a [u8],
    i: usize,
}

impl Lexer<'_> {
    fn at(&self, k: usize) -> Option<u8> {
        self.b.get(k).copied()
    }
    fn skip_ws(&mut self) {
        loop {
            while self.at(self.i).is_some_and(|c| c.is_ascii_whitespace()) {
                self.i += 1;
            }
            if self.at(self.i) == Some(b'/') && matches!(self.at(self.i + 1), Some(b'/' | b'*')) {
                self.i = skip_token(self.b, self.i);
            } else {
                return;
            }
        }
    }
    fn peek(&mut self) -> Option<u8> {
        self.skip_ws();
        self.at(self.i)
    }
    fn ident(&mut self) -> Option<(usize, usize)> {
        self.skip_ws();
        let s = self.i;
        while self.at(self.i).is_some_and(is_ident_byte) {
            self.i += 1;
        }
        (self.i > s).then_some((s, self.i))
    }
}

fn parse_tree(text: &str) -> Result<Node, String> {
    let mut lx = Lexer {
        b: text.as_bytes(),
        i: 0,
    };
    // Skip `#![enable(...)]` extension attributes.
    while lx.peek() == Some(b'#') {
        while lx.at(lx.i).is_some_and(|c| c != b']') {
            lx.i += 1;
        }
        if lx.at(lx.i).is_none() {
            return Err("unclosed `#![` attribute".into());
        }
        lx.i += 1;
    }
    parse_value(&mut lx, 0)
}

fn parse_value(lx: &mut Lexer, depth: usize) -> Result<Node, String> {
    if depth > MAX_NESTING {
        return Err(format!("nested deeper than {MAX_NESTING} levels"));
    }
    let c = lx.peek().ok_or("unexpected end")?;
    let start = lx.i;
    match c {
        b'(' => parse_paren(lx, start, depth),
        b'[' => {
            lx.i += 1;
            let items = parse_items(lx, b']', depth)?;
            Ok(Node {
                start,
                end: lx.i,
                kind: NodeKind::Seq(items),
            })
        }
        b'{' => {
            // Maps: skip to the matching brace.
            let mut d = 0usize;
            while let Some(ch) = lx.at(lx.i) {
                match ch {
                    b'{' => d += 1,
                    b'}' => {
                        d = d.saturating_sub(1);
                        if d == 0 {
                            lx.i += 1;
                            break;
                        }
                    }
                    b'"' | b'\'' | b'/' => {
                        lx.i = skip_token(lx.b, lx.i);
                        continue;
                    }
                    _ => {}
                }
                lx.i += 1;
            }
            Ok(Node {
                start,
                end: lx.i.min(lx.b.len()),
                kind: NodeKind::Atom,
            })
        }
        b'"' | b'\'' => {
            // A string or a char literal: skip to the closing quote, honouring escapes.
            lx.i = skip_token(lx.b, lx.i);
            Ok(Node {
                start,
                end: lx.i,
                kind: NodeKind::Atom,
            })
        }
        b'r' if matches!(lx.at(lx.i + 1), Some(b'"' | b'#')) => {
            lx.i = skip_token(lx.b, lx.i);
            Ok(Node {
                start,
                end: lx.i,
                kind: NodeKind::Atom,
            })
        }
        c if c.is_ascii_alphabetic() || c == b'_' => {
            lx.ident();
            if lx.peek() == Some(b'(') {
                let p = lx.i;
                let mut n = parse_paren(lx, p, depth)?;
                n.start = start;
                Ok(n)
            } else {
                Ok(Node {
                    start,
                    end: lx.i,
                    kind: NodeKind::Atom,
                })
            }
        }
        _ => {
            // Number or other scalar.
            while lx.at(lx.i).is_some_and(|c| {
                !matches!(c, b',' | b')' | b']' | b'}') && !c.is_ascii_whitespace()
            }) {
                lx.i += 1;
            }
            if lx.i == start {
                return Err(format!("unexpected character `{}`", c as char));
            }
            Ok(Node {
                start,
                end: lx.i,
                kind: NodeKind::Atom,
            })
        }
    }
}

fn parse_paren(lx: &mut Lexer, start: usize, depth: usize) -> Result<Node, String> {
    let open = lx.i;
    lx.i += 1; // '('
    // Struct if the first token is `ident :` (not `::`).
    let save = lx.i;
    let is_struct = match lx.ident() {
        Some(_) => lx.peek() == Some(b':') && lx.at(lx.i + 1) != Some(b':'),
        None => false,
    };
    lx.i = save;
    if is_struct {
        let mut fields = Vec::new();
        loop {
            if lx.peek() == Some(b')') {
                lx.i += 1;
                break;
            }
            let (ks, ke) = lx.ident().ok_or("expected a field name")?;
            let key = String::from_utf8_lossy(&lx.b[ks..ke]).to_string();
            if lx.peek() != Some(b':') {
                return Err(format!("expected `:` after `{key}`"));
            }
            lx.i += 1;
            let v = parse_value(lx, depth + 1)?;
            fields.push((key, ks, v));
            match lx.peek() {
                Some(b',') => lx.i += 1,
                Some(b')') => {}
                _ => return Err("expected `,` or `)`".into()),
            }
        }
        Ok(Node {
            start,
            end: lx.i,
            kind: NodeKind::Struct { open, fields },
        })
    } else {
        let items = parse_items(lx, b')', depth)?;
        Ok(Node {
            start,
            end: lx.i,
            kind: NodeKind::Seq(items),
        })
    }
}

fn parse_items(lx: &mut Lexer, close: u8, depth: usize) -> Result<Vec<Node>, String> {
    let mut items = Vec::new();
    loop {
        match lx.peek() {
            Some(c) if c == close => {
                lx.i += 1;
                return Ok(items);
            }
            None => return Err("unexpected end".into()),
            _ => {}
        }
        items.push(parse_value(lx, depth + 1)?);
        match lx.peek() {
            Some(b',') => lx.i += 1,
            Some(c) if c == close => {}
            _ => return Err(format!("expected `,` or `{}`", close as char)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: &str = "Scene(\n  name: \"x\",\n  bodies: [\n    (name: \"a\", mass_kg: 1.0),\n    (name: \"b\", mass_kg: 2.0, p: (1.0, 2.0)),\n  ],\n)";

    #[test]
    fn locate_by_name_and_index() {
        let (s, e) = locate(T, "bodies.b.mass_kg").unwrap();
        assert_eq!(&T[s..e], "2.0");
        assert_eq!(line_col(T, s), (5, 26));
        let (s, e) = locate(T, "bodies[0].mass_kg").unwrap();
        assert_eq!(&T[s..e], "1.0");
        let (s, e) = locate(T, "bodies.b.p.1").unwrap();
        assert_eq!(&T[s..e], "2.0");
    }

    #[test]
    fn override_replaces_and_inserts() {
        let t = apply_override(T, "f", "bodies.a.mass_kg=5.5").unwrap();
        assert!(t.contains("(name: \"a\", mass_kg: 5.5)"));
        let t = apply_override(T, "f", "bodies.a.com_m=(1.0, 0.0, 0.0)").unwrap();
        let (s, e) = locate(&t, "bodies.a.com_m").unwrap();
        assert_eq!(&t[s..e], "(1.0, 0.0, 0.0)");
        assert!(apply_override(T, "f", "bodies.zz.mass_kg=1").is_err());
        assert!(apply_override(T, "f", "nonsense").is_err());
        // Through a newtype `Some((…))`: replace a field, insert a missing one.
        let t = "Scene(docking: Some((seat_depth_m: 0.25)))";
        let r = apply_override(t, "f", "docking.seat_depth_m=0.3").unwrap();
        assert_eq!(r, "Scene(docking: Some((seat_depth_m: 0.3)))");
        let r = apply_override(t, "f", "docking.contact=Rigid").unwrap();
        assert_eq!(
            r,
            "Scene(docking: Some((contact: Rigid, seat_depth_m: 0.25)))"
        );
    }

    #[test]
    fn field_at_finds_the_innermost_field() {
        assert_eq!(field_at_offset(T, offset_of(T, 5, 27)), "bodies.b.mass_kg");
    }
}
