//! `shadowlab check`: a map rendered from its first spawn point with its lights, under shadow
//! maps and shadow volumes with the planner on and off, measured against the exact reference.
//! One [`MapCheck`] per map; a map that cannot be loaded or rendered says why instead.

use crate::images::{Mask, MaskValue};
use crate::options::{Options, Technique};
use crate::run::{FrameRequest, Renderer};
use crate::scene::Scene;
use crate::scene_file::{
    CameraSection, LightSource, LightsSection, LoadReport, MapSection, SceneFile,
};
use crate::truth::metrics::{compare_where, near_boundary, ratio};
use crate::truth::{ExactMasks, Reference};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// One map's line.
#[derive(Debug, Clone, Default, Serialize)]
pub struct MapCheck {
    /// The bsp path inside the data set.
    pub map: String,
    pub load_ms: f64,
    /// Triangles of the world that cast shadows.
    pub world_triangles: usize,
    /// Edges of the world's triangles with one triangle (open) and with more than two.
    pub open_edges: usize,
    pub non_manifold_edges: usize,
    /// Planar world surfaces whose own triangles overlap, and those triangles: the lit pass
    /// adds a light twice where they do (docs/checks.md).
    pub overlapping_surfaces: usize,
    pub overlapping_triangles: usize,
    pub lights: usize,
    /// `entities` (the map's light entities) or `placed` (one above each spawn point and item).
    pub light_source: &'static str,
    pub runs: Vec<Run>,
    /// Per technique, how the planner changed the masks.
    pub planner: Vec<PlannerDifference>,
    pub warnings: Vec<String>,
    /// Why the map could not be checked (then nothing above but its name is filled).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// One technique with the planner on or off.
#[derive(Debug, Clone, Serialize)]
pub struct Run {
    pub technique: Technique,
    pub planner: bool,
    pub frame_ms: f64,
    pub receiver_pixels: usize,
    /// Receiver pixels decided otherwise than the reference, in percent.
    pub error_percent: f64,
    /// The same, leaving out the 1-pixel band around the reference's shadow boundaries.
    pub error_excl_boundary_percent: f64,
    /// The wrong pixels whose exact answer texture alpha does not decide (the reference with
    /// alpha-tested casters drawn solid agrees there), in percent of all receiver pixels: what
    /// a technique built from geometry alone (volumes) can be held to; the rest of
    /// `error_percent` lies in the holes of alpha-tested casters.
    pub error_beside_alpha_percent: f64,
}

/// Pixels whose decision the planner changed (masks with it on against off).
#[derive(Debug, Clone, Serialize)]
pub struct PlannerDifference {
    pub technique: Technique,
    pub differing_pixels: usize,
    /// Those outside the 1-pixel band around the reference's shadow boundaries.
    pub beyond_edge_band: usize,
    /// The same with the decisions that change pixels by design turned off
    /// ([`crate::plan::without_pixel_changing_decisions`]): what the conservative decisions
    /// changed, which should be nothing.
    pub conservative_beyond_edge_band: usize,
}

/// The scene `check` renders: `bsp` of the data set at `data`, the camera at the first spawn
/// point, the map's light entities or placed lights.
pub fn scene_file(data: &Path, bsp: &str) -> SceneFile {
    SceneFile {
        map: Some(MapSection {
            bsp: bsp.to_string(),
            data: Some(data.to_path_buf()),
            paks: None,
        }),
        camera: CameraSection {
            spawn: Some(0),
            ..CameraSection::default()
        },
        lights: LightsSection {
            from: LightSource::EntitiesOrPlaced,
            ..LightsSection::default()
        },
        ..SceneFile::default()
    }
}

/// Loads and checks one map under `techniques`; its line says why where it cannot.
pub fn check_map(
    renderer: &mut Renderer,
    data: &Path,
    bsp: &str,
    options: &Options,
    techniques: &[Technique],
) -> MapCheck {
    let mut line = MapCheck {
        map: bsp.to_string(),
        ..MapCheck::default()
    };
    let start = Instant::now();
    let (scene, report) = match scene_file(data, bsp).build(options) {
        Ok(loaded) => loaded,
        Err(e) => {
            line.error = Some(format!("cannot load: {e}"));
            return line;
        }
    };
    line.load_ms = start.elapsed().as_secs_f64() * 1e3;
    describe(&mut line, &scene, report);
    if let Err(e) = measure_runs(renderer, &scene, (options, techniques), &mut line) {
        line.error = Some(format!("cannot render: {e}"));
    }
    line
}

fn describe(line: &mut MapCheck, scene: &Scene, report: LoadReport) {
    if let Some(c) = report.counts {
        line.world_triangles = c.caster_triangles;
        line.open_edges = c.edges.open;
        line.non_manifold_edges = c.edges.non_manifold;
        line.overlapping_surfaces = c.overlapping_surfaces;
        line.overlapping_triangles = c.overlapping_triangles;
    }
    line.lights = scene.lights.len();
    line.light_source = if scene.lights.iter().any(|l| l.name.starts_with("placed")) {
        "placed"
    } else {
        "entities"
    };
    line.warnings = report.warnings;
}

/// Renders each technique with the planner on and off and measures each frame.
fn measure_runs(
    renderer: &mut Renderer,
    scene: &Scene,
    (options, techniques): (&Options, &[Technique]),
    line: &mut MapCheck,
) -> Result<(), crate::gl::RenderError> {
    renderer.load_scene(scene)?;
    let mut exact = ExactMasks::default();
    // Only a scene with alpha-tested casters has pixels whose answer alpha decides.
    let mut solid = has_alpha_tested_casters(scene)
        .then(|| ExactMasks::with_reference(Reference::build_with(scene, false)));
    let request = FrameRequest {
        masks: true,
        ..FrameRequest::default()
    };
    for &technique in techniques {
        let mut masks: Vec<Vec<Mask>> = Vec::new();
        for planner in [true, false] {
            let mut o = options.clone();
            o.technique = technique;
            o.plan.enabled = planner;
            let frame = renderer.render_with(scene, &o, request)?;
            let gbuffer = frame.gbuffer.as_ref().expect("masks were asked for");
            let m = exact.measure(scene, gbuffer, &frame.masks);
            let rates = m.total.rates();
            let beside_alpha = match solid.as_mut() {
                Some(solid) => {
                    let s = solid.measure(scene, gbuffer, &frame.masks);
                    errors_beside_alpha(&frame.masks, &m.exact, &s.exact)
                }
                None => m.total.false_shadow + m.total.false_lit,
            };
            line.runs.push(Run {
                technique,
                planner,
                frame_ms: frame.frame_ms,
                receiver_pixels: m.total.receiver_pixels,
                error_percent: rates.total * 100.0,
                error_excl_boundary_percent: rates.total_excl_boundary * 100.0,
                error_beside_alpha_percent: 100.0 * ratio(beside_alpha, m.total.receiver_pixels),
            });
            masks.push(frame.masks);
        }
        let mut d = planner_difference(technique, &masks[0], &masks[1], &exact);
        // Those decisions are shadow-map forms: a volume frame is the planner's frame.
        d.conservative_beyond_edge_band = if technique == Technique::ShadowVolume {
            d.beyond_edge_band
        } else {
            let mut o = crate::plan::without_pixel_changing_decisions(options);
            o.technique = technique;
            o.plan.enabled = true;
            let conservative = renderer.render_with(scene, &o, request)?.masks;
            planner_difference(technique, &conservative, &masks[1], &exact).beyond_edge_band
        };
        line.planner.push(d);
    }
    Ok(())
}

fn has_alpha_tested_casters(scene: &Scene) -> bool {
    scene
        .materials
        .iter()
        .any(|m| m.visible && m.casts_shadows && m.alpha_test.is_some())
}

/// Wrong decisions of `masks` on pixels where the exact mask and the one traced with
/// alpha-tested casters solid agree.
fn errors_beside_alpha(masks: &[Mask], exact: &[Mask], solid: &[Mask]) -> usize {
    masks
        .iter()
        .zip(exact.iter().zip(solid))
        .map(|(m, (e, s))| {
            let c = compare_where(m, e, |i| e.values[i] == s.values[i]);
            c.false_shadow + c.false_lit
        })
        .sum()
}

/// Pixels where the masks with the planner on and off disagree, in all and outside the
/// reference's boundary band.
fn planner_difference(
    technique: Technique,
    on: &[Mask],
    off: &[Mask],
    exact: &ExactMasks,
) -> PlannerDifference {
    let mut d = PlannerDifference {
        technique,
        differing_pixels: 0,
        beyond_edge_band: 0,
        conservative_beyond_edge_band: 0,
    };
    for (a, b) in on.iter().zip(off) {
        let reference = exact.get(a.width, a.height, a.light);
        for (i, (x, y)) in a.values.iter().zip(&b.values).enumerate() {
            let (px, py) = (i as u32 % a.width, i as u32 / a.width);
            // Only receivers count, as in the error: elsewhere the mask decides nothing.
            let receiver = reference.is_none_or(|r| r.get(px, py) != MaskValue::NotReceiver);
            if x == y || !receiver {
                continue;
            }
            d.differing_pixels += 1;
            if !reference.is_some_and(|r| near_boundary(r, px, py)) {
                d.beyond_edge_band += 1;
            }
        }
    }
    d
}
