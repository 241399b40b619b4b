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
}

impl LoadedScene {
    /// An error about the field at `path`, located in the text.
    pub fn error_at(&self, path: &str, message: impl Into<String>) -> SceneError {
        let (line, col) = locate(&self.text, path)
            .map(|(s, _)| line_col(&self.text, s))
            .unwrap_or((0, 0));
        SceneError {
            file: self.file.clone(),
            line,
            col,
            field: path.to_string(),
            message: message.into(),
        }
    }
}

/// Reads, overrides, parses and validates a scene file.
pub fn load_scene_file(path: &Path, overrides: &[String]) -> Result<LoadedScene, SceneError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        file: file.clone(),
        line: 0,
        col: 0,
        field: String::new(),
        message: format!("cannot read the scene: {e}"),
    })?;
    load_scene_str(&text, &file, overrides)
}

/// Parses and validates scene text; `file` names it in errors.
pub fn load_scene_str(
    text: &str,
    file: &str,
    overrides: &[String],
) -> Result<LoadedScene, SceneError> {
    let mut text = text.to_string();
    for o in overrides {
        text = apply_override(&text, file, o)?;
    }
    let scene: Scene = parse_ron(&text, file)?;
    let loaded = LoadedScene {
        scene,
        text,
        file: file.to_string(),
    };
    if let Err((path, message)) = super::validate::validate(&loaded.scene) {
        return Err(loaded.error_at(&path, message));
    }
    Ok(loaded)
}

/// Parses any RON document (e.g. a trials file), with serde errors located like scene errors.
/// Optional fields may be written bare (`duration_s: 30.0`) or as `Some(30.0)`.
pub fn parse_ron<T: serde::de::DeserializeOwned>(text: &str, file: &str) -> Result<T, SceneError> {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(text)
        .map_err(|e| SceneError {
            file: file.to_string(),
            line: e.span.start.line,
            col: e.span.start.col,
            field: field_at(text, e.span.start.line, e.span.start.col),
            message: e.code.to_string(),
        })
}

/// Applies one `path=value` override to scene text. The value is RON (`3.5`, `true`,
/// `(1.0, 2.0, 3.0)`, `"name"`). A field absent from the text is inserted into its struct.
pub fn apply_override(text: &str, file: &str, assignment: &str) -> Result<String, SceneError> {
    let err = |message: String| SceneError {
        file: format!("{file} (--set {assignment})"),
        line: 0,
        col: 0,
        field: assignment
            .split('=')
            .next()
            .unwrap_or("")
            .trim()
            .to_string(),
        message,
    };
    let (path, value) = assignment
        .split_once('=')
        .ok_or_else(|| err("expected `path=value`".into()))?;
    let (path, value) = (path.trim(), value.trim());
    if path.is_empty() || value.is_empty() {
        return Err(err("expected `path=value`".into()));
    }
    let root = parse_tree(text).map_err(|m| err(format!("cannot read the scene text: {m}")))?;
    let segs = split_path(path);
    // Navigate to the parent; the last segment may be missing (then insert it).
    let mut node = &root;
    for (i, seg) in segs.iter().enumerate() {
        let last = i + 1 == segs.len();
        match child(text, node, seg) {
            Some(c) => {
                if last {
                    let mut out = String::with_capacity(text.len() + value.len());
                    out.push_str(&text[..c.start]);
                    out.push_str(value);
                    out.push_str(&text[c.end..]);
                    return Ok(out);
                }
                node = c;
            }
            None => {
                if last && let NodeKind::Struct { open, .. } = &unwrap_newtype(node).kind {
                    let mut out = String::with_capacity(text.len() + value.len() + 8);
                    out.push_str(&text[..open + 1]);
                    out.push_str(&format!("{seg}: {value}, "));
                    out.push_str(&text[open + 1..]);
                    return Ok(out);
                }
                return Err(err(format!(
                    "no field `{seg}` at `{}`",
                    segs[..i].join(".")
                )));
            }
        }
    }
    Err(err("empty path".into()))
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
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// The innermost field path that contains a line/column (for serde errors).
fn field_at(text: &str, line: usize, col: usize) -> String {
    let Ok(root) = parse_tree(text) else {
        return String::new();
    };
    // Byte offset of (line, col).
    let mut offset = text.len();
    let mut l = 1;
    for (i, ch) in text.char_indices() {
        if l == line {
            for (c, (j, ch2)) in (1..).zip(text[i..].char_indices()) {
                if c == col || ch2 == '\n' {
                    offset = i + j;
                    break;
                }
            }
            break;
        }
        if ch == '\n' {
            l += 1;
        }
    }
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
    fn skip_ws(&mut self) {
        loop {
            while self.i < self.b.len() && self.b[self.i].is_ascii_whitespace() {
                self.i += 1;
            }
            if self.b[self.i..].starts_with(b"//") {
                while self.i < self.b.len() && self.b[self.i] != b'\n' {
                    self.i += 1;
                }
            } else if self.b[self.i..].starts_with(b"/*") {
                let mut depth = 0;
                while self.i < self.b.len() {
                    if self.b[self.i..].starts_with(b"/*") {
                        depth += 1;
                        self.i += 2;
                    } else if self.b[self.i..].starts_with(b"*/") {
                        depth -= 1;
                        self.i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        self.i += 1;
                    }
                }
            } else {
                return;
            }
        }
    }
    fn peek(&mut self) -> Option<u8> {
        self.skip_ws();
        self.b.get(self.i).copied()
    }
    fn ident(&mut self) -> Option<(usize, usize)> {
        self.skip_ws();
        let s = self.i;
        while self.i < self.b.len()
            && (self.b[self.i].is_ascii_alphanumeric() || self.b[self.i] == b'_')
        {
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
        while lx.i < lx.b.len() && lx.b[lx.i] != b']' {
            lx.i += 1;
        }
        lx.i += 1;
    }
    parse_value(&mut lx)
}

fn parse_value(lx: &mut Lexer) -> Result<Node, String> {
    let c = lx.peek().ok_or("unexpected end")?;
    let start = lx.i;
    match c {
        b'(' => parse_paren(lx, start),
        b'[' => {
            lx.i += 1;
            let items = parse_items(lx, b']')?;
            Ok(Node {
                start,
                end: lx.i,
                kind: NodeKind::Seq(items),
            })
        }
        b'{' => {
            // Maps: skip to the matching brace.
            let mut depth = 0;
            while lx.i < lx.b.len() {
                match lx.b[lx.i] {
                    b'{' => depth += 1,
                    b'}' => {
                        depth -= 1;
                        if depth == 0 {
                            lx.i += 1;
                            break;
                        }
                    }
                    _ => {}
                }
                lx.i += 1;
            }
            Ok(Node {
                start,
                end: lx.i,
                kind: NodeKind::Atom,
            })
        }
        q @ (b'"' | b'\'') => {
            // A string or a char literal: skip to the closing quote, honouring escapes.
            lx.i += 1;
            while lx.i < lx.b.len() && lx.b[lx.i] != q {
                if lx.b[lx.i] == b'\\' {
                    lx.i += 1;
                }
                lx.i += 1;
            }
            lx.i += 1;
            Ok(Node {
                start,
                end: lx.i.min(lx.b.len()),
                kind: NodeKind::Atom,
            })
        }
        c if c.is_ascii_alphabetic() || c == b'_' => {
            lx.ident();
            if lx.peek() == Some(b'(') {
                let p = lx.i;
                let mut n = parse_paren(lx, p)?;
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
            while lx.i < lx.b.len()
                && !matches!(lx.b[lx.i], b',' | b')' | b']' | b'}')
                && !lx.b[lx.i].is_ascii_whitespace()
            {
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

fn parse_paren(lx: &mut Lexer, start: usize) -> Result<Node, String> {
    let open = lx.i;
    lx.i += 1; // '('
    // Struct if the first token is `ident :` (not `::`).
    let save = lx.i;
    let is_struct = match lx.ident() {
        Some(_) => lx.peek() == Some(b':') && lx.b.get(lx.i + 1) != Some(&b':'),
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
            let v = parse_value(lx)?;
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
        let items = parse_items(lx, b')')?;
        Ok(Node {
            start,
            end: lx.i,
            kind: NodeKind::Seq(items),
        })
    }
}

fn parse_items(lx: &mut Lexer, close: u8) -> Result<Vec<Node>, String> {
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
        items.push(parse_value(lx)?);
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
        assert_eq!(field_at(T, 5, 27), "bodies.b.mass_kg");
    }
}
