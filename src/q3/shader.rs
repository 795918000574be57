//! Quake 3 shader scripts (`scripts/*.shader`), reduced to what shadowlab needs: which image a
//! surface shows, whether it is alpha-tested, blended, two-sided, sky, fog or not drawn, and the
//! shadow rules that follow from that.
//!
//! Parsing is tolerant, as Quake 3's is: a malformed shader block is skipped with a warning naming
//! its line and the rest of the file still loads. Nothing here panics, whatever the input.

use crate::scene::{AlphaFunc, Cull, Material};
use std::collections::HashMap;
use thiserror::Error;

/// Something wrong in a script that was skipped or ignored; parsing went on.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("line {line}: {message}")]
pub struct ShaderWarning {
    /// 1-based line in the script.
    pub line: usize,
    pub message: String,
}

/// The `surfaceparm` flags shadowlab cares about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SurfaceParms {
    pub nodraw: bool,
    pub sky: bool,
    pub trans: bool,
    pub nolightmap: bool,
    pub fog: bool,
    pub nonsolid: bool,
}

/// One shader of a script, summarised.
#[derive(Debug, Clone, PartialEq)]
pub struct ShaderDef {
    /// Lower-case, with forward slashes (see [`normalize_name`]).
    pub name: String,
    /// Line of the name in its script.
    pub line: usize,
    /// Image of the first stage that has a real one (`map`, `clampMap`, or `animMap`'s first
    /// frame; not `$lightmap`, `$whiteimage` or `*white`), normalized like names.
    pub texture: Option<String>,
    /// `alphaFunc` of the stage that gave `texture`.
    pub alpha_func: Option<AlphaFunc>,
    pub cull: Cull,
    pub surfaceparms: SurfaceParms,
    /// The first stage blends with what is behind it (a `blendFunc` other than `GL_ONE GL_ZERO`)
    /// and does not write depth (no `depthWrite`).
    /// A `$lightmap` first stage followed by a `blendFunc filter` texture is the usual opaque
    /// lightmapped wall, so it is not blended.
    pub blended: bool,
    pub has_lightmap_stage: bool,
    /// `surfaceparm sky` or `skyParms`.
    pub sky: bool,
    /// `deformVertexes autosprite` or `autosprite2`: camera-facing quads (flares, flames).
    pub deform_autosprite: bool,
    pub stage_count: usize,
}

impl ShaderDef {
    /// Blended surfaces (glass, flames, beams): drawn over the scene, so they neither cast nor
    /// receive shadows in shadowlab.
    pub fn translucent(&self) -> bool {
        self.blended
    }

    /// Whether the surface takes part as an occluder. Not for invisible (nodraw, fog) or sky
    /// surfaces, blended ones, or autosprites (their geometry is not what is seen). Nonsolid but
    /// opaque surfaces such as alpha-tested foliage do cast.
    pub fn casts_shadows(&self) -> bool {
        let p = &self.surfaceparms;
        !(p.nodraw || p.fog || self.sky || self.translucent() || self.deform_autosprite)
    }

    /// Whether the surface is drawn as geometry at all (sky is drawn as a backdrop, not here).
    pub fn visible(&self) -> bool {
        let p = &self.surfaceparms;
        !(p.nodraw || p.fog || self.sky)
    }

    /// Whether dynamic light and shadow land on the surface: drawn and opaque.
    pub fn receives_light(&self) -> bool {
        self.visible() && !self.translucent()
    }

    /// The scene material for this shader, given the index of its loaded texture.
    pub fn to_material(&self, texture: Option<usize>) -> Material {
        Material {
            name: self.name.clone(),
            texture,
            alpha_test: self.alpha_func,
            cull: self.cull,
            translucent: self.translucent(),
            casts_shadows: self.casts_shadows(),
            receives_light: self.receives_light(),
            visible: self.visible(),
        }
    }
}

/// Shader and image names as Quake 3 compares them: case-insensitive, either slash.
pub fn normalize_name(name: &str) -> String {
    name.trim().replace('\\', "/").to_ascii_lowercase()
}

/// `path` without its extension (a dot after the last slash).
fn strip_extension(path: &str) -> &str {
    let file_start = path.rfind('/').map_or(0, |i| i + 1);
    match path[file_start..].rfind('.') {
        Some(dot) => &path[..file_start + dot],
        None => path,
    }
}

/// The files Quake 3 tries for an image reference, in order: the extension is ignored and `.tga`
/// comes before `.jpg`. Lower-case, forward slashes. Empty for an empty path.
pub fn image_candidates(path: &str) -> Vec<String> {
    let norm = normalize_name(path);
    let base = strip_extension(&norm);
    if base.is_empty() {
        return Vec::new();
    }
    vec![format!("{base}.tga"), format!("{base}.jpg")]
}

/// Every shader of many scripts, by name.
#[derive(Debug, Clone, Default)]
pub struct ShaderLibrary {
    shaders: HashMap<String, ShaderDef>,
    warnings: Vec<(String, ShaderWarning)>,
}

impl ShaderLibrary {
    pub fn new() -> Self {
        Self::default()
    }

    /// Parses one script and adds its shaders. As in Quake 3, the first definition of a name wins:
    /// a later one (in this script or a later script) is ignored, so add scripts in the order the
    /// game reads them. Warnings are logged and kept with `file_name`. Returns how many shaders
    /// were newly defined.
    pub fn add_script(&mut self, text: &str, file_name: &str) -> usize {
        let (defs, warnings) = parse_shader_script(text);
        for w in warnings {
            log::warn!("{file_name}: {w}");
            self.warnings.push((file_name.to_string(), w));
        }
        let mut added = 0;
        for def in defs {
            if !self.shaders.contains_key(&def.name) {
                self.shaders.insert(def.name.clone(), def);
                added += 1;
            }
        }
        added
    }

    /// The shader for a name as maps and models write it: case-insensitive, and, as Quake 3
    /// does, the extension is ignored (models often name `foo.tga` for the shader `foo`).
    pub fn get(&self, name: &str) -> Option<&ShaderDef> {
        let norm = normalize_name(name);
        self.shaders
            .get(strip_extension(&norm))
            .or_else(|| self.shaders.get(&norm))
    }

    pub fn len(&self) -> usize {
        self.shaders.len()
    }

    pub fn is_empty(&self) -> bool {
        self.shaders.is_empty()
    }

    pub fn iter(&self) -> impl Iterator<Item = &ShaderDef> {
        self.shaders.values()
    }

    /// Every warning so far, with the file it came from.
    pub fn warnings(&self) -> &[(String, ShaderWarning)] {
        &self.warnings
    }
}

// ---------------------------------------------------------------------------------------------
// Tokenizer

#[derive(Debug, Clone, Copy)]
struct Token<'a> {
    text: &'a str,
    /// Line where the token starts; directives end where the line does.
    line: usize,
    quoted: bool,
}

impl Token<'_> {
    fn is(&self, brace: &str) -> bool {
        !self.quoted && self.text == brace
    }
    fn is_brace(&self) -> bool {
        self.is("{") || self.is("}")
    }
}

/// Splits a script into words, braces and quoted strings, dropping `//` and `/* */` comments.
/// Braces are tokens of their own even when written against a word.
fn tokenize<'a>(text: &'a str, warnings: &mut Vec<ShaderWarning>) -> Vec<Token<'a>> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let mut line = 1;
    let comment_at = |i: usize| b[i] == b'/' && matches!(b.get(i + 1), Some(b'/' | b'*'));
    // Every index where the text is sliced holds an ASCII byte, so slices are on char boundaries.
    while i < b.len() {
        let c = b[i];
        if c == b'\n' {
            line += 1;
            i += 1;
        } else if c <= b' ' {
            i += 1;
        } else if comment_at(i) && b[i + 1] == b'/' {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if comment_at(i) {
            let start_line = line;
            i += 2;
            loop {
                if i >= b.len() {
                    warnings.push(ShaderWarning {
                        line: start_line,
                        message: "`/*` comment never closed".to_string(),
                    });
                    break;
                }
                if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                    i += 2;
                    break;
                }
                if b[i] == b'\n' {
                    line += 1;
                }
                i += 1;
            }
        } else if c == b'{' || c == b'}' {
            out.push(Token {
                text: &text[i..i + 1],
                line,
                quoted: false,
            });
            i += 1;
        } else if c == b'"' {
            // A string ends at its quote or, if that is missing, at the end of the line.
            let start = i + 1;
            let mut j = start;
            while j < b.len() && b[j] != b'"' && b[j] != b'\n' {
                j += 1;
            }
            out.push(Token {
                text: &text[start..j],
                line,
                quoted: true,
            });
            if b.get(j) == Some(&b'"') {
                i = j + 1;
            } else {
                warnings.push(ShaderWarning {
                    line,
                    message: "string not closed on its line".to_string(),
                });
                i = j;
            }
        } else {
            let start = i;
            while i < b.len() {
                let c = b[i];
                if c <= b' ' || c == b'{' || c == b'}' || c == b'"' || comment_at(i) {
                    break;
                }
                i += 1;
            }
            out.push(Token {
                text: &text[start..i],
                line,
                quoted: false,
            });
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Parser

#[derive(Debug, Default)]
struct Stage {
    image: Option<String>,
    lightmap: bool,
    alpha_func: Option<AlphaFunc>,
    blended: bool,
    /// `depthWrite`: a blended stage that still writes depth, which Quake 3 draws as occluding.
    depth_write: bool,
}

/// Directives written alone on a line; such a word followed by `{` is a stage, not a shader
/// name, when guessing where a broken block ends.
const LONE_DIRECTIVES: &[&str] = &[
    "nopicmip",
    "nomipmaps",
    "polygonoffset",
    "portal",
    "entitymergable",
    "fogonly",
    "noshadows",
    "nofog",
    "depthwrite",
    "detail",
];

fn starts_line(toks: &[Token], k: usize) -> bool {
    k == 0 || toks[k - 1].line < toks[k].line
}

/// Whether `toks[k]` looks like a shader name: a plain word first on its line and directly
/// followed by `{`.
fn name_candidate(toks: &[Token], k: usize) -> bool {
    let t = &toks[k];
    !t.quoted
        && !t.is_brace()
        && starts_line(toks, k)
        && toks.get(k + 1).is_some_and(|n| n.is("{"))
        && !LONE_DIRECTIVES.contains(&t.text.to_ascii_lowercase().as_str())
}

/// A name with a slash (`textures/...`, `models/...`) before `{` can only start a new shader.
fn path_name_at(toks: &[Token], k: usize) -> bool {
    name_candidate(toks, k) && toks[k].text.contains('/')
}

/// Index just past the `}` matching the `{` at `open` (or the end): Quake 3's own skipping.
fn skip_braced(toks: &[Token], open: usize) -> usize {
    let mut depth = 0usize;
    for (k, t) in toks.iter().enumerate().skip(open) {
        if t.is("{") {
            depth += 1;
        } else if t.is("}") {
            depth = depth.saturating_sub(1);
            if depth == 0 {
                return k + 1;
            }
        }
    }
    toks.len()
}

/// Parses every shader of a script. Broken blocks are skipped with a warning; see the module
/// notes. Names are normalized with [`normalize_name`].
pub fn parse_shader_script(text: &str) -> (Vec<ShaderDef>, Vec<ShaderWarning>) {
    let mut warnings = Vec::new();
    let toks = tokenize(text, &mut warnings);
    let mut defs = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        let t = toks[i];
        if t.is("{") {
            warnings.push(ShaderWarning {
                line: t.line,
                message: "block without a shader name skipped".to_string(),
            });
            i = skip_braced(&toks, i);
        } else if t.is("}") {
            warnings.push(ShaderWarning {
                line: t.line,
                message: "`}` without a block".to_string(),
            });
            i += 1;
        } else if !toks.get(i + 1).is_some_and(|n| n.is("{")) {
            warnings.push(ShaderWarning {
                line: t.line,
                message: format!("`{}` is not followed by `{{`; ignored", t.text),
            });
            i += 1;
        } else {
            let (def, next) = parse_block(&toks, i, &mut warnings);
            defs.extend(def);
            i = next;
        }
    }
    (defs, warnings)
}

/// Parses the shader named at `toks[at]` (followed by `{`). Returns it, or `None` if the block
/// is broken, and where parsing goes on (always after `at`).
///
/// A missing `}` is found when a path-like name opens a block inside this one, or when a third
/// level of braces opens (stages do not nest). Parsing then resumes at the name that most likely
/// starts the next shader, so one broken block loses only itself.
fn parse_block(
    toks: &[Token],
    at: usize,
    warnings: &mut Vec<ShaderWarning>,
) -> (Option<ShaderDef>, usize) {
    let name = toks[at];
    let mut def = ShaderDef {
        name: normalize_name(name.text),
        line: name.line,
        texture: None,
        alpha_func: None,
        cull: Cull::Back,
        surfaceparms: SurfaceParms::default(),
        blended: false,
        has_lightmap_stage: false,
        sky: false,
        deform_autosprite: false,
        stage_count: 0,
    };
    let mut stages: Vec<Stage> = Vec::new();
    // The stage being read, with the index of its `{`.
    let mut stage: Option<(Stage, usize)> = None;
    let skipped = |warnings: &mut Vec<ShaderWarning>, why: String, next: usize| {
        warnings.push(ShaderWarning {
            line: name.line,
            message: format!("shader `{}` skipped: {why}", name.text),
        });
        (None, next)
    };
    let mut j = at + 2;
    loop {
        let Some(t) = toks.get(j).copied() else {
            return skipped(
                warnings,
                "end of file inside its block".to_string(),
                toks.len(),
            );
        };
        if t.is("}") {
            match stage.take() {
                Some((s, _)) => stages.push(s),
                None => {
                    finish(&mut def, stages);
                    return (Some(def), j + 1);
                }
            }
            j += 1;
        } else if t.is("{") {
            if let Some((_, open)) = stage {
                let restart = [j, open]
                    .into_iter()
                    .filter(|&k| k > at + 1 && name_candidate(toks, k - 1))
                    .map(|k| k - 1)
                    .next()
                    .or_else(|| ((j + 1)..toks.len()).find(|&k| path_name_at(toks, k)));
                let next = restart.unwrap_or_else(|| skip_braced(toks, at + 1));
                return skipped(
                    warnings,
                    format!("`{{` inside a stage on line {}", t.line),
                    next,
                );
            }
            stage = Some((Stage::default(), j));
            j += 1;
        } else if path_name_at(toks, j) {
            return skipped(
                warnings,
                format!("`}}` missing before `{}` on line {}", t.text, t.line),
                j,
            );
        } else {
            let mut end = j + 1;
            while end < toks.len() && toks[end].line == t.line && !toks[end].is_brace() {
                end += 1;
            }
            let words: Vec<&str> = toks[j..end].iter().map(|t| t.text).collect();
            match &mut stage {
                Some((s, _)) => stage_directive(s, &words, t.line, warnings),
                None => shader_directive(&mut def, &words, t.line, warnings),
            }
            j = end;
        }
    }
}

fn finish(def: &mut ShaderDef, stages: Vec<Stage>) {
    if let Some(s) = stages.iter().find(|s| s.image.is_some()) {
        def.texture = s.image.clone();
        def.alpha_func = s.alpha_func;
    }
    // A blended first stage that writes depth (e.g. metal grids: filter + alphaFunc + depthWrite)
    // occludes like opaque geometry, so it is not translucent.
    def.blended = stages.first().is_some_and(|s| s.blended && !s.depth_write);
    def.has_lightmap_stage = stages.iter().any(|s| s.lightmap);
    def.sky |= def.surfaceparms.sky;
    def.stage_count = stages.len();
}

fn warn(warnings: &mut Vec<ShaderWarning>, line: usize, message: String) {
    warnings.push(ShaderWarning { line, message });
}

/// A directive outside stages; `words[0]` is the keyword. Unknown ones are ignored.
fn shader_directive(
    def: &mut ShaderDef,
    words: &[&str],
    line: usize,
    warnings: &mut Vec<ShaderWarning>,
) {
    let key = words[0].to_ascii_lowercase();
    let arg = words.get(1).map(|a| a.to_ascii_lowercase());
    match key.as_str() {
        "surfaceparm" => {
            let p = &mut def.surfaceparms;
            match arg.as_deref() {
                Some("nodraw") => p.nodraw = true,
                Some("sky") => p.sky = true,
                Some("trans") => p.trans = true,
                Some("nolightmap") => p.nolightmap = true,
                Some("fog") => p.fog = true,
                Some("nonsolid") => p.nonsolid = true,
                _ => {}
            }
        }
        // Quake 3 names the face that is removed; our enum names the face that is culled the
        // same way, with the default (`front`) drawing front faces.
        "cull" => match arg.as_deref() {
            Some("front") => def.cull = Cull::Back,
            Some("back" | "backside" | "backsided") => def.cull = Cull::Front,
            Some("none" | "disable" | "twosided") => def.cull = Cull::None,
            _ => warn(
                warnings,
                line,
                format!("bad `cull {}`", words[1..].join(" ")),
            ),
        },
        "skyparms" => def.sky = true,
        "deformvertexes" => {
            if matches!(arg.as_deref(), Some("autosprite" | "autosprite2")) {
                def.deform_autosprite = true;
            }
        }
        _ => {}
    }
}

/// A directive inside a stage. Unknown ones are ignored.
fn stage_directive(s: &mut Stage, words: &[&str], line: usize, warnings: &mut Vec<ShaderWarning>) {
    let key = words[0].to_ascii_lowercase();
    match key.as_str() {
        // animMap's first argument is its frequency; its first frame stands for the animation.
        "map" | "clampmap" | "animmap" => {
            let image = words.get(if key == "animmap" { 2 } else { 1 });
            match image {
                Some(img) if img.eq_ignore_ascii_case("$lightmap") => s.lightmap = true,
                // `$whiteimage`, `*white` and the like are built-in images, not files.
                Some(img) if img.starts_with('$') || img.starts_with('*') => {}
                Some(img) => s.image = Some(normalize_name(img)),
                None => warn(warnings, line, format!("`{}` without an image", words[0])),
            }
        }
        "alphafunc" => {
            let arg = words.get(1).map(|a| a.to_ascii_lowercase());
            s.alpha_func = match arg.as_deref() {
                Some("gt0") => Some(AlphaFunc::Gt0),
                Some("lt128") => Some(AlphaFunc::Lt128),
                Some("ge128") => Some(AlphaFunc::Ge128),
                _ => {
                    warn(warnings, line, format!("bad `{}`", words.join(" ")));
                    s.alpha_func
                }
            };
        }
        "depthwrite" => s.depth_write = true,
        "blendfunc" => {
            let args: Vec<String> = words[1..].iter().map(|a| a.to_ascii_lowercase()).collect();
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            // Words after the factors are ignored: scripts sometimes put a second directive on
            // the same line, which Quake 3 reads as such.
            match args.as_slice() {
                ["add" | "filter" | "blend", ..] => s.blended = true,
                [src, dst, ..] => s.blended = !(*src == "gl_one" && *dst == "gl_zero"),
                _ => warn(warnings, line, format!("bad `{}`", words.join(" "))),
            }
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCRIPT: &str = r#"// A test script.
/* A block comment
   over lines { with braces } */
textures/base_wall/Concrete
{
	qer_editorimage textures/base_wall/concrete.tga
	{
		map $lightmap
		rgbGen identity
	}
	{
		map textures\base_wall\Concrete.tga // comment after a path
		blendFunc filter
	}
}

textures/base_support/grate
{
	surfaceparm trans
	surfaceparm nonsolid
	cull none
	{
		map textures/base_support/grate.tga
		alphaFunc GE128
		depthWrite
	}
	{
		map $lightmap
		blendFunc GL_DST_COLOR GL_ZERO
		depthFunc equal
	}
}

textures/fx/beam
{
	surfaceparm trans
	cull back
	{ clampMap textures/fx/beam.tga
	  blendfunc add }
}

textures/skies/stars
{
	surfaceparm sky
	surfaceparm noimpact
	skyparms - 512 -
}

textures/fx/flame
{
	deformVertexes autosprite
	{
		animMap 10 textures/fx/flame1.tga textures/fx/flame2.tga
		blendFunc GL_ONE GL_ZERO
	}
}
"#;

    fn by_name<'a>(defs: &'a [ShaderDef], name: &str) -> &'a ShaderDef {
        defs.iter().find(|d| d.name == name).unwrap()
    }

    #[test]
    fn parses_a_commented_script() {
        let (defs, warnings) = parse_shader_script(SCRIPT);
        assert!(warnings.is_empty(), "{warnings:?}");
        let names: Vec<&str> = defs.iter().map(|d| d.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "textures/base_wall/concrete",
                "textures/base_support/grate",
                "textures/fx/beam",
                "textures/skies/stars",
                "textures/fx/flame"
            ]
        );
        assert_eq!(defs[0].line, 4);
    }

    #[test]
    fn lightmapped_wall_is_opaque_and_casts() {
        let (defs, _) = parse_shader_script(SCRIPT);
        let d = by_name(&defs, "textures/base_wall/concrete");
        assert_eq!(
            d.texture.as_deref(),
            Some("textures/base_wall/concrete.tga")
        );
        assert!(d.has_lightmap_stage);
        assert!(!d.blended);
        assert_eq!(d.alpha_func, None);
        assert_eq!(d.cull, Cull::Back);
        assert_eq!(d.stage_count, 2);
        assert!(d.casts_shadows() && d.visible() && d.receives_light());
    }

    #[test]
    fn alpha_tested_grate_casts_from_both_sides() {
        let (defs, _) = parse_shader_script(SCRIPT);
        let d = by_name(&defs, "textures/base_support/grate");
        assert_eq!(
            d.texture.as_deref(),
            Some("textures/base_support/grate.tga")
        );
        assert_eq!(d.alpha_func, Some(AlphaFunc::Ge128));
        assert_eq!(d.cull, Cull::None);
        assert!(d.surfaceparms.trans && d.surfaceparms.nonsolid);
        assert!(!d.blended);
        assert!(d.casts_shadows() && d.receives_light());
        let m = d.to_material(Some(7));
        assert_eq!(m.alpha_test, Some(AlphaFunc::Ge128));
        assert_eq!(m.texture, Some(7));
        assert!(m.casts_shadows && !m.translucent);
    }

    #[test]
    fn additive_beam_is_translucent() {
        let (defs, _) = parse_shader_script(SCRIPT);
        let d = by_name(&defs, "textures/fx/beam");
        assert_eq!(d.texture.as_deref(), Some("textures/fx/beam.tga"));
        assert_eq!(d.cull, Cull::Front);
        assert!(d.blended && d.translucent());
        assert!(!d.casts_shadows() && !d.receives_light() && d.visible());
    }

    #[test]
    fn sky_is_not_visible() {
        let (defs, _) = parse_shader_script(SCRIPT);
        let d = by_name(&defs, "textures/skies/stars");
        assert!(d.sky && d.surfaceparms.sky);
        assert_eq!(d.texture, None);
        assert!(!d.visible() && !d.casts_shadows() && !d.receives_light());
        // skyParms alone also makes a sky.
        let (defs, _) = parse_shader_script("sky2 { skyParms env/x 512 - }");
        assert!(defs[0].sky && !defs[0].visible());
    }

    #[test]
    fn anim_map_uses_its_first_frame() {
        let (defs, _) = parse_shader_script(SCRIPT);
        let d = by_name(&defs, "textures/fx/flame");
        assert_eq!(d.texture.as_deref(), Some("textures/fx/flame1.tga"));
        assert!(!d.blended, "GL_ONE GL_ZERO is opaque");
        assert!(d.deform_autosprite && !d.casts_shadows() && d.visible());
    }

    #[test]
    fn unbalanced_block_is_skipped_and_the_next_one_parsed() {
        let text = "textures/a/bad\n{\n\t{\n\t\tmap textures/a/bad.tga\n\t// stage never closed\n}\n\ntextures/a/good\n{\n\t{\n\t\tmap textures/a/good.tga\n\t}\n}\n";
        let (defs, warnings) = parse_shader_script(text);
        assert_eq!(defs.len(), 1);
        assert_eq!(defs[0].name, "textures/a/good");
        assert_eq!(defs[0].texture.as_deref(), Some("textures/a/good.tga"));
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert_eq!(warnings[0].line, 1);
        assert!(warnings[0].message.contains("textures/a/bad"));
        assert!(warnings[0].message.contains("line 8"), "{}", warnings[0]);
    }

    #[test]
    fn broken_blocks_without_slashes_or_stages_recover_too() {
        // Shader `}` missing, next name without a slash: found at the third brace level.
        let text = "bad\n{\n{\nmap a.tga\n}\nsun\n{\nnopicmip\n{\nmap b.tga\n}\n}\n";
        let (defs, warnings) = parse_shader_script(text);
        assert_eq!(defs.len(), 1);
        assert_eq!(defs[0].name, "sun");
        assert_eq!(defs[0].texture.as_deref(), Some("b.tga"));
        assert_eq!(warnings.len(), 1);
        // No stages: found by the path-like next name.
        let text =
            "textures/x/bad\n{\nsurfaceparm nodraw\ntextures/x/good\n{\nsurfaceparm trans\n}\n";
        let (defs, warnings) = parse_shader_script(text);
        assert_eq!(defs.len(), 1);
        assert_eq!(defs[0].name, "textures/x/good");
        assert!(defs[0].surfaceparms.trans && !defs[0].surfaceparms.nodraw);
        assert_eq!(warnings[0].line, 1);
    }

    #[test]
    fn end_of_file_inside_a_block_warns() {
        let text = "a/ok { }\n\n  a/cut\n{\n  { map x.tga\n";
        let (defs, warnings) = parse_shader_script(text);
        assert_eq!(defs.len(), 1);
        assert_eq!(defs[0].name, "a/ok");
        assert_eq!(warnings.len(), 1);
        assert_eq!(warnings[0].line, 3);
        assert!(warnings[0].message.contains("end of file"));
    }

    #[test]
    fn garbage_never_panics() {
        for text in [
            "",
            "{",
            "}",
            "}}{{",
            "a",
            "a {",
            "a { {",
            "a { { { } } }",
            "\"unterminated",
            "/* open",
            "a { map }",
            "a { { animmap 10 } }",
            "a { { blendfunc } cull }",
            "é { { map ü.tga } }",
            "\0\u{1}",
            "a { b/c { d } } }",
        ] {
            let _ = parse_shader_script(text);
        }
    }

    #[test]
    fn built_in_images_and_extra_words_are_handled() {
        // Seen in real scripts: a second directive on the blendFunc line.
        let text = "a/b {\n { map *white\n blendFunc GL_DST_COLOR GL_ZERO rgbGen identity }\n { map $whiteimage }\n { map a/b.jpg } }";
        let (defs, warnings) = parse_shader_script(text);
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(defs[0].texture.as_deref(), Some("a/b.jpg"));
        assert!(defs[0].blended && !defs[0].has_lightmap_stage);
        assert_eq!(defs[0].stage_count, 3);
    }

    #[test]
    fn first_definition_wins() {
        let mut lib = ShaderLibrary::new();
        assert_eq!(
            lib.add_script("textures/a/x { { map first.tga } }", "a.shader"),
            1
        );
        assert_eq!(
            lib.add_script(
                "TEXTURES\\A\\X { { map second.tga } }\ntextures/a/y { }",
                "b.shader"
            ),
            1
        );
        assert_eq!(lib.len(), 2);
        let x = lib.get("Textures/A/X").unwrap();
        assert_eq!(x.texture.as_deref(), Some("first.tga"));
        // Quake 3 ignores the extension when looking a shader up.
        assert_eq!(lib.get("textures\\a\\x.tga").unwrap().name, "textures/a/x");
        assert!(lib.get("textures/a/z").is_none());
        assert!(lib.warnings().is_empty());
    }

    #[test]
    fn library_keeps_warnings_with_their_file() {
        let mut lib = ShaderLibrary::new();
        lib.add_script("\n}\n", "broken.shader");
        assert_eq!(lib.warnings().len(), 1);
        assert_eq!(lib.warnings()[0].0, "broken.shader");
        assert_eq!(lib.warnings()[0].1.line, 2);
    }

    #[test]
    fn image_candidates_try_tga_then_jpg() {
        assert_eq!(
            image_candidates("Textures\\A/B.JPG"),
            ["textures/a/b.tga", "textures/a/b.jpg"]
        );
        assert_eq!(
            image_candidates("textures/a.dir/b"),
            ["textures/a.dir/b.tga", "textures/a.dir/b.jpg"]
        );
        assert!(image_candidates("").is_empty());
    }

    #[test]
    fn a_blended_alpha_tested_stage_with_depth_write_occludes() {
        let script = "textures/t/metalgrid\n{\n cull none\n {\n  map textures/t/metalgrid.tga\n  blendFunc filter\n  alphaFunc GE128\n  depthWrite\n }\n}\ntextures/t/glass\n{\n {\n  map textures/t/glass.tga\n  blendFunc filter\n  alphaFunc GE128\n }\n}\n";
        let (defs, warnings) = parse_shader_script(script);
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(defs.len(), 2);
        assert!(!defs[0].blended && defs[0].casts_shadows());
        assert_eq!(defs[0].alpha_func, Some(AlphaFunc::Ge128));
        assert!(defs[1].blended && !defs[1].casts_shadows());
    }
}
