//! The viewer's egui interface: the control panel, the 3D view with mouse look, and the
//! overlays (timings, help, walkthrough, error progress). Keys are read here too.

use super::option_panel::{self, Field, FieldValue};
use super::script::ViewMode;
use super::state::{Action, Pending, ViewerState};
use super::walkthrough;
use crate::frame::Frame;
use crate::options::Technique;
use crate::scene::LightKind;
use egui::{Color32, Key, Pos2, Rect, Sense, Stroke, TextureHandle, Vec2};

/// The images the view can show, uploaded by the window loop.
#[derive(Default)]
pub struct Textures {
    /// The rendered frame (or, in the walkthrough, the buffer of the step), uploaded.
    pub view: Option<TextureHandle>,
    /// The rendered frame's own GL texture, shown where it lies (no read-back, no upload):
    /// the texture, its size in pixels and the part of it the frame fills, flipped (GL's
    /// rows run bottom up). Shown instead of `view` when set.
    pub frame: Option<(egui::TextureId, Vec2, Rect)>,
    /// Depth map, stencil heat map or error image, with a caption.
    pub aux: Option<(TextureHandle, String)>,
}

/// The key help (F1).
pub const HELP: &[(&str, &str)] = &[
    ("W A S D", "move; Space / C up and down; Shift faster"),
    ("drag in the view", "look around"),
    (
        "1 - 9",
        "cycle light 1-9's technique: none, shadow map, shadow volume, auto",
    ),
    ("0", "cycle the technique of every light without its own"),
    ("Tab", "select the next light"),
    ("F1", "this help"),
    ("F2", "timings and counts overlay"),
    (
        "F3",
        "view: scene, depth map, stencil counts, error against the reference",
    ),
    (
        "F4 / F5 / F6",
        "selected light's volumes / its silhouette edges / shadow-map texels",
    ),
    (
        "F7",
        "walkthrough on or off; Page Up / Page Down: previous / next step",
    ),
    ("F8", "compute the error image against the exact reference"),
    (
        "E",
        "live error: each frame's masks sampled against the exact reference, per light",
    ),
    (
        "F9",
        "record the camera path (again: stop and save camera-path.txt)",
    ),
    ("F10", "replay the last recorded path"),
    (
        "P / , / .",
        "the scene's motion (players, moving lights): play or pause / step back / step on",
    ),
    (
        "G",
        "grab the selected light: it moves with the camera (G again drops it)",
    ),
    ("F11", "vsync on or off"),
    ("F12", "screenshot of the window"),
    ("Esc", "quit"),
];

/// Keys, unless a text field has the keyboard.
fn keys(ctx: &egui::Context, state: &mut ViewerState) {
    if ctx.egui_wants_keyboard_input() {
        state.fly = Default::default();
        return;
    }
    let look = state.fly.look;
    ctx.input(|i| {
        state.fly.forward = i.key_down(Key::W);
        state.fly.back = i.key_down(Key::S);
        state.fly.left = i.key_down(Key::A);
        state.fly.right = i.key_down(Key::D);
        state.fly.up = i.key_down(Key::Space);
        state.fly.down = i.key_down(Key::C);
        state.fly.fast = i.modifiers.shift;
    });
    state.fly.look = look;
    let pressed = |k: Key| ctx.input(|i| i.key_pressed(k));
    let digits = [
        Key::Num1,
        Key::Num2,
        Key::Num3,
        Key::Num4,
        Key::Num5,
        Key::Num6,
        Key::Num7,
        Key::Num8,
        Key::Num9,
    ];
    for (i, k) in digits.iter().enumerate() {
        if pressed(*k) {
            state.cycle_light_technique(i);
        }
    }
    if pressed(Key::Num0) {
        state.cycle_technique();
    }
    if pressed(Key::Tab) && !state.scene.lights.is_empty() {
        state.selected_light = (state.selected_light + 1) % state.scene.lights.len();
    }
    if pressed(Key::F1) {
        state.show_help = !state.show_help;
    }
    if pressed(Key::F2) {
        state.show_timings = !state.show_timings;
    }
    if pressed(Key::F3) {
        state.cycle_view();
    }
    if pressed(Key::F4) {
        state.overlays.volumes = !state.overlays.volumes;
    }
    if pressed(Key::F5) {
        state.overlays.silhouettes = !state.overlays.silhouettes;
    }
    if pressed(Key::F6) {
        state.overlays.texel_grid = !state.overlays.texel_grid;
    }
    if pressed(Key::F7) {
        state.walkthrough = match state.walkthrough {
            Some(_) => None,
            None => Some(0),
        };
    }
    if pressed(Key::PageDown) {
        state.step_walkthrough(1);
    }
    if pressed(Key::PageUp) {
        state.step_walkthrough(-1);
    }
    if pressed(Key::F8) {
        state.view = ViewMode::Error;
    }
    if pressed(Key::E) {
        state.live_error.on = !state.live_error.on;
    }
    if pressed(Key::F9) {
        let next = state.recording.is_none().then(|| "camera-path.txt".into());
        if let Err(e) = state.record(next) {
            state.status = e;
        }
    }
    if pressed(Key::F10)
        && let Some(p) = state.last_path.clone()
        && let Err(e) = state.replay(p)
    {
        state.status = e;
    }
    if pressed(Key::F11) {
        state.vsync = !state.vsync;
    }
    if pressed(Key::F12) {
        let file = state.next_screenshot();
        state.pending.push(Pending::Screenshot(file));
    }
    if pressed(Key::P) {
        state.clock.playing = !state.clock.playing;
    }
    if pressed(Key::Comma) {
        state.clock.playing = false;
        state.advance_motion(0.0, -1);
    }
    if pressed(Key::Period) {
        state.clock.playing = false;
        state.advance_motion(0.0, 1);
    }
    if pressed(Key::G) {
        state.toggle_grab();
    }
    if pressed(Key::Escape) {
        state.quit = true;
    }
}

/// The scene's motion: its time, play or pause, step.
fn motion_panel(ui: &mut egui::Ui, state: &mut ViewerState) {
    let m = &state.scene.motion;
    ui.label(format!(
        "Motion: {:.2} s · {} animated, {} walking, {} lights moving",
        state.clock.time,
        m.rigs.len(),
        m.walks.len(),
        m.lights.len()
    ));
    ui.horizontal(|ui| {
        let label = if state.clock.playing {
            "pause (P)"
        } else {
            "play (P)"
        };
        if ui.button(label).clicked() {
            state.clock.playing = !state.clock.playing;
        }
        if ui.button("step back (,)").clicked() {
            state.clock.playing = false;
            state.advance_motion(0.0, -1);
        }
        if ui.button("step on (.)").clicked() {
            state.clock.playing = false;
            state.advance_motion(0.0, 1);
        }
    });
}

/// Each light's running sampled error, the frame's and what the sampling cost.
fn live_error(ui: &mut egui::Ui, state: &ViewerState) {
    let live = &state.live_error;
    if live.building() {
        ui.label("building the reference (a BVH of the casters)…");
        return;
    }
    let Some(frame) = &live.last_frame else {
        ui.label("waiting for a frame with masks…");
        return;
    };
    let pct = |x: f64| format!("{:.2}%", 100.0 * x);
    let o = &state.options.estimate;
    ui.label(format!(
        "last sampled frame: {} [{}, {}], {} rays in {:.1} ms",
        pct(frame.total.value),
        pct(frame.total.low),
        pct(frame.total.high),
        frame.rays,
        live.trace_ms,
    ));
    ui.label(format!(
        "sampling costs {} of frame time (estimate.budget {}); lights over {} sampled frames:",
        pct(live.share()),
        pct(f64::from(o.budget)),
        o.window
    ));
    egui::Grid::new("live_error").striped(true).show(ui, |ui| {
        for (light, e) in live.lights() {
            ui.label(format!("light {light}"));
            ui.label(e.technique.map_or("–".into(), |t| t.to_string()));
            ui.label(format!(
                "{} ± {}",
                pct(e.error.value),
                pct((e.error.high - e.error.low) / 2.0)
            ));
            ui.label(format!("{} frames", e.frames));
            ui.end_row();
        }
    });
}

fn technique_combo(ui: &mut egui::Ui, id: &str, value: &mut Option<Technique>, default: &str) {
    let text = value.map_or(default.to_string(), |t| t.to_string());
    egui::ComboBox::from_id_salt(id)
        .selected_text(text)
        .show_ui(ui, |ui| {
            ui.selectable_value(value, None, default);
            for t in Technique::ALL {
                ui.selectable_value(value, Some(*t), t.as_str());
            }
        });
}

fn light_panel(ui: &mut egui::Ui, state: &mut ViewerState) {
    let global = state.options.technique;
    egui::ComboBox::from_label("technique (all lights)")
        .selected_text(global.as_str())
        .show_ui(ui, |ui| {
            for t in Technique::ALL {
                ui.selectable_value(&mut state.options.technique, *t, t.as_str());
            }
        });
    ui.separator();
    ui.label(format!("Lights ({})", state.scene.lights.len()));
    for i in 0..state.scene.lights.len() {
        ui.horizontal(|ui| {
            let l = &state.scene.lights[i];
            let kind = match l.kind {
                LightKind::Spot { .. } => "spot",
                LightKind::Omni => "omni",
            };
            let label = format!("{} {} ({kind})", i + 1, l.name);
            if ui
                .selectable_label(state.selected_light == i, label)
                .clicked()
            {
                state.selected_light = i;
            }
            let own = state.options.technique_for(i);
            let mut over = (own != global
                || state.options.lighting.techniques.contains(&format!("{i}:")))
            .then_some(own);
            let before = over;
            technique_combo(ui, &format!("light-tech-{i}"), &mut over, "default");
            if over != before {
                state.options.set_technique_for(i, over);
            }
        });
    }
    let lights = state.scene.lights.len();
    if lights > 0 {
        let l = state.selected_light.min(lights - 1);
        ui.label(format!("Selected light {}", l + 1));
        let mut light = state.scene.lights[l].clone();
        let before = light.clone();
        ui.horizontal(|ui| {
            ui.label("position");
            ui.add(egui::DragValue::new(&mut light.position.x).speed(2.0));
            ui.add(egui::DragValue::new(&mut light.position.y).speed(2.0));
            ui.add(egui::DragValue::new(&mut light.position.z).speed(2.0));
        });
        ui.horizontal(|ui| {
            ui.label("radius");
            ui.add(
                egui::DragValue::new(&mut light.radius)
                    .speed(4.0)
                    .range(1.0..=100_000.0),
            );
            if let LightKind::Spot { cutoff_deg, .. } = &mut light.kind {
                ui.label("cutoff");
                ui.add(
                    egui::DragValue::new(cutoff_deg)
                        .speed(0.5)
                        .range(1.0..=89.0),
                );
            }
        });
        if light != before {
            std::sync::Arc::make_mut(&mut state.scene).lights[l] = light;
        }
        ui.horizontal_wrapped(|ui| {
            for (text, action) in [
                ("to camera", Action::LightToCamera),
                ("aim at view", Action::AimLightAtView),
                ("add spot", Action::AddSpot),
                ("add omni", Action::AddOmni),
                ("remove", Action::RemoveLight),
            ] {
                if ui.button(text).clicked() {
                    state.act(action);
                }
            }
        });
    } else if ui.button("add omni at camera").clicked() {
        state.act(Action::AddOmni);
    }
    if !state.scene.models.is_empty() {
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("model");
            let m = state.selected_model.min(state.scene.models.len() - 1);
            egui::ComboBox::from_id_salt("model")
                .selected_text(format!("{m}: {}", state.scene.models[m].name))
                .show_ui(ui, |ui| {
                    for (i, model) in state.scene.models.iter().enumerate() {
                        ui.selectable_value(
                            &mut state.selected_model,
                            i,
                            format!("{i}: {}", model.name),
                        );
                    }
                });
        });
        ui.horizontal(|ui| {
            if ui.button("place at view").clicked() {
                state.act(Action::PlaceModel);
            }
            if ui.button("copy at view").clicked() {
                state.act(Action::CopyModel);
            }
        });
    }
}

fn view_panel(ui: &mut egui::Ui, state: &mut ViewerState, depth_images: usize) {
    ui.horizontal(|ui| {
        for m in ViewMode::ALL {
            ui.radio_value(&mut state.view, m, m.name());
        }
    });
    if state.view == ViewMode::Depth && depth_images > 1 {
        ui.add(egui::Slider::new(&mut state.face, 0..=depth_images - 1).text("view / face"));
    }
    ui.checkbox(
        &mut state.overlays.volumes,
        "selected light's volumes (red z-fail, green z-pass)",
    );
    ui.checkbox(&mut state.overlays.silhouettes, "its silhouette edges");
    ui.checkbox(
        &mut state.overlays.texel_grid,
        "shadow-map texels (checkerboard)",
    );
    ui.checkbox(&mut state.show_timings, "timings and counts");
    let mut walk = state.walkthrough.is_some();
    ui.horizontal(|ui| {
        if ui.checkbox(&mut walk, "walkthrough").changed() {
            state.walkthrough = walk.then_some(0);
        }
        if walk {
            if ui.button("<").clicked() {
                state.step_walkthrough(-1);
            }
            if ui.button(">").clicked() {
                state.step_walkthrough(1);
            }
            ui.label(format!(
                "step {} of {}",
                state.walkthrough.unwrap_or(0) + 1,
                state.steps.len()
            ));
        }
    });
    ui.horizontal(|ui| {
        let recording = state.recording.is_some();
        if ui
            .button(if recording {
                "stop recording"
            } else {
                "record path"
            })
            .clicked()
        {
            let next = (!recording).then(|| "camera-path.txt".into());
            if let Err(e) = state.record(next) {
                state.status = e;
            }
        }
        if let Some(p) = state.last_path.clone()
            && ui.button("replay").clicked()
            && let Err(e) = state.replay(p)
        {
            state.status = e;
        }
        if ui.button("screenshot").clicked() {
            let f = state.next_screenshot();
            state.pending.push(Pending::Screenshot(f));
        }
        ui.checkbox(&mut state.vsync, "vsync");
    });
}

fn field_widget(ui: &mut egui::Ui, f: &mut Field) -> bool {
    match &mut f.value {
        FieldValue::Bool(b) => ui.checkbox(b, f.key).changed(),
        FieldValue::Choice { choices, index } => {
            let mut changed = false;
            ui.horizontal(|ui| {
                egui::ComboBox::from_id_salt(f.key)
                    .selected_text(choices[*index])
                    .show_ui(ui, |ui| {
                        for (i, c) in choices.iter().enumerate() {
                            changed |= ui.selectable_value(index, i, *c).changed();
                        }
                    });
                ui.label(f.key);
            });
            changed
        }
        FieldValue::Float { value, min, max } => {
            ui.horizontal(|ui| {
                let speed = ((*max - *min) / 1000.0).clamp(0.001, 10.0);
                let r = ui.add(egui::DragValue::new(value).speed(speed).range(*min..=*max));
                ui.label(f.key);
                r.changed()
            })
            .inner
        }
        FieldValue::Integer { value, min, max } => {
            ui.horizontal(|ui| {
                let r = ui.add(
                    egui::DragValue::new(value)
                        .speed(1.0)
                        .range(*min as i64..=*max as i64),
                );
                ui.label(f.key);
                r.changed()
            })
            .inner
        }
        FieldValue::Text(t) => {
            ui.horizontal(|ui| {
                let r = ui.add(egui::TextEdit::singleline(t).desired_width(110.0));
                ui.label(f.key);
                r.lost_focus()
            })
            .inner
        }
    }
}

fn options_panel(ui: &mut egui::Ui, state: &mut ViewerState) {
    let mut fields = option_panel::fields(&state.options);
    let mut groups: Vec<&'static str> = fields.iter().map(|f| f.group).collect();
    groups.dedup();
    for g in groups {
        egui::CollapsingHeader::new(g)
            .id_salt(format!("group-{g}"))
            .show(ui, |ui| {
                for f in fields.iter_mut().filter(|f| f.group == g) {
                    let tip = format!("{}\n\ndefault: {}", f.meaning, f.default);
                    let scope = ui.scope(|ui| field_widget(ui, f));
                    scope.response.on_hover_text(tip);
                    if scope.inner
                        && field_changed(f, &state.options)
                        && let Err(e) = option_panel::apply(&mut state.options, f)
                    {
                        state.status = e.to_string();
                    }
                }
            });
    }
}

/// Whether a field's value differs from the options (the widget changed it).
fn field_changed(f: &Field, options: &crate::options::Options) -> bool {
    options
        .get(f.key)
        .map(|v| v != f.value.text())
        .unwrap_or(false)
        && match &f.value {
            // Floats print differently from how they parse; compare as numbers.
            FieldValue::Float { value, .. } => options
                .get(f.key)
                .ok()
                .and_then(|v| v.parse::<f64>().ok())
                .is_none_or(|v| (v - *value).abs() > 1e-9 * value.abs().max(1.0)),
            _ => true,
        }
}

/// Per-stage sums of a frame's passes, in first-seen order.
fn stages(frame: &Frame) -> Vec<(String, f64)> {
    let mut out: Vec<(String, f64)> = Vec::new();
    for p in &frame.passes {
        let stage = p.pass.stage.name().to_string();
        match out.iter_mut().find(|(n, _)| *n == stage) {
            Some(e) => e.1 += p.ms,
            None => out.push((stage, p.ms)),
        }
    }
    out
}

/// Which preset the options equal, or how they differ from the paper's frame.
fn paper_line(options: &crate::options::Options) -> String {
    use crate::presets::Preset;
    if let Some(p) = Preset::matching(options) {
        return format!("preset {}", p.name());
    }
    let keys: Vec<String> = Preset::Paper
        .differences(options)
        .into_iter()
        .map(|d| d.key)
        .collect();
    let shown = keys.iter().take(4).cloned().collect::<Vec<_>>().join(", ");
    let more = keys.len().saturating_sub(4);
    match more {
        0 => format!("differs from the paper's frame in {shown}"),
        _ => format!("differs from the paper's frame in {shown} and {more} more"),
    }
}

fn timings(ui: &mut egui::Ui, state: &ViewerState, frame: &Frame) {
    let stages = stages(frame);
    let max = stages.iter().map(|s| s.1).fold(0.1, f64::max);
    let clock = if frame
        .passes
        .iter()
        .any(|p| p.clock == crate::plan::pass::Clock::Gpu)
    {
        "passes: GPU timer queries"
    } else {
        "passes: CPU time around glFinish"
    };
    let span = match frame.completed {
        true => "call to completion",
        false => "call to submission",
    };
    ui.label(format!("frame {:.1} ms ({span}; {clock})", frame.frame_ms));
    if frame.passes_frames_ago > 0 {
        ui.label(format!(
            "GPU passes as timed {} frame(s) back (read without waiting)",
            frame.passes_frames_ago
        ));
    }
    ui.label(format!("waits for the GPU: {}", frame.syncs.describe()));
    for (name, ms) in &stages {
        ui.horizontal(|ui| {
            let (rect, _) = ui.allocate_exact_size(Vec2::new(150.0, 12.0), Sense::hover());
            let w = (ms / max) as f32 * rect.width();
            ui.painter().rect_filled(
                Rect::from_min_size(rect.min, Vec2::new(w.max(1.0), rect.height())),
                2.0,
                Color32::from_rgb(90, 140, 220),
            );
            ui.label(format!("{name} {ms:.2} ms"));
        });
    }
    let p = &frame.plan_stats;
    ui.label(format!(
        "surfaces {} of {}, triangles {}",
        p.surfaces_visible, p.surfaces, p.triangles_visible
    ));
    if let Some(v) = &p.vis {
        ui.label(format!(
            "BSP leaves {}: {} outside the PVS, {} outside the frustum",
            v.leaves, v.leaves_outside_pvs, v.leaves_outside_frustum
        ));
    }
    let lights_on = (0..state.scene.lights.len())
        .filter(|&i| state.options.light_enabled(i))
        .count();
    ui.label(format!(
        "lights drawn {lights_on} of {}",
        state.scene.lights.len()
    ));
    ui.label(paper_line(&state.options));
    ui.label(format!(
        "planner: {} lights planned, {} culled (frustum {}, PVS {}), {} without casters",
        p.lights_planned,
        p.lights_culled_frustum + p.lights_culled_pvs,
        p.lights_culled_frustum,
        p.lights_culled_pvs,
        p.lights_without_casters
    ));
    ui.label(format!(
        "casters {} drawn, {} culled; receivers {} drawn, {} culled; scissor {:.0}% of the frame",
        p.casters_drawn,
        p.casters_culled,
        p.receivers_drawn,
        p.receivers_culled,
        100.0 * p.scissor_fraction
    ));
    let c = &frame.cache;
    ui.label(format!(
        "cache: maps {} reused, {} drawn; volume parts {} reused, {} built; depth {}",
        c.maps_reused,
        c.maps_rendered,
        c.volume_parts_reused,
        c.volume_parts_built,
        if c.depth_reused { "reused" } else { "read" }
    ));
    for choice in &p.choices {
        ui.label(format!("auto: {choice}"));
    }
    if !frame.volumes.is_empty() {
        let quads: usize = frame.volumes.iter().map(|v| v.quads).sum();
        let caps: usize = frame.volumes.iter().map(|v| v.cap_triangles).sum();
        let zpass: usize = frame.volumes.iter().map(|v| v.zpass_parts).sum();
        let zfail: usize = frame.volumes.iter().map(|v| v.zfail_parts).sum();
        let clipped: usize = frame.volumes.iter().map(|v| v.parts_depth_clipped).sum();
        let merged: usize = frame.volumes.iter().map(|v| v.merged_parts).sum();
        let chunks: usize = frame.volumes.iter().map(|v| v.chunks_merged).sum();
        let left_out: usize = frame.volumes.iter().map(|v| v.triangles_clipped).sum();
        let refits: usize = frame.volumes.iter().map(|v| v.depth_fits_reused).sum();
        let kept = frame.volumes.iter().filter(|v| v.draws_reused).count();
        ui.label(format!(
            "volumes: {quads} quads, {caps} cap triangles, {zfail} z-fail / {zpass} z-pass parts \
             ({} split, {clipped} depth-clipped, {merged} merged from {chunks} chunks), {} \
             stencil pass(es); {left_out} triangles left out wholly clipped, {refits} depth \
             fits reused, {kept} lights' draws kept",
            p.split_parts, p.stencil_passes
        ));
    }
    frame_time_graph(ui, state);
}

/// The last frames' times as a line.
fn frame_time_graph(ui: &mut egui::Ui, state: &ViewerState) {
    let (rect, _) = ui.allocate_exact_size(Vec2::new(260.0, 50.0), Sense::hover());
    ui.painter()
        .rect_filled(rect, 2.0, Color32::from_black_alpha(120));
    let hist: Vec<f64> = state.frame_ms.iter().copied().collect();
    let top = hist.iter().copied().fold(1.0, f64::max);
    let n = super::state::HISTORY as f32;
    let points: Vec<Pos2> = hist
        .iter()
        .enumerate()
        .map(|(i, ms)| {
            Pos2::new(
                rect.left() + rect.width() * i as f32 / n,
                rect.bottom() - rect.height() * (*ms / top) as f32,
            )
        })
        .collect();
    ui.painter().add(egui::Shape::line(
        points,
        Stroke::new(1.5, Color32::LIGHT_GREEN),
    ));
    ui.label(format!(
        "frame time, last {} frames (max {top:.0} ms)",
        hist.len()
    ));
}

/// Draws the whole interface; returns the 3D view's size in pixels.
pub fn draw(
    ui: &mut egui::Ui,
    state: &mut ViewerState,
    frame: Option<&Frame>,
    textures: &Textures,
    depth_images: usize,
) -> [u32; 2] {
    let ctx = ui.ctx().clone();
    keys(&ctx, state);
    egui::Panel::left("controls")
        .resizable(true)
        .default_size(330.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                ui.heading(format!("shadowlab · {}", state.scene.name));
                ui.label(format!(
                    "{} triangles, {} lights · F1 help",
                    state.scene.triangle_count(),
                    state.scene.lights.len()
                ));
                if !state.status.is_empty() {
                    ui.colored_label(Color32::LIGHT_YELLOW, &state.status);
                }
                ui.separator();
                if !state.scene.motion.is_still() {
                    motion_panel(ui, state);
                    ui.separator();
                }
                light_panel(ui, state);
                ui.separator();
                view_panel(ui, state, depth_images);
                ui.separator();
                ui.label("Options (hover for meaning and default)");
                options_panel(ui, state);
            });
        });
    let mut size = [16, 16];
    egui::CentralPanel::default().show(ui, |ui| {
        let avail = ui.available_size();
        let ppp = ui.pixels_per_point();
        size = [
            ((avail.x * ppp) as u32).max(16),
            ((avail.y * ppp) as u32).max(16),
        ];
        let full = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        let uploaded = |t: &TextureHandle| (t.id(), t.size_vec2(), full);
        let shown = match (&state.view, &textures.aux, state.walkthrough) {
            (_, _, Some(_)) => textures.view.as_ref().map(uploaded),
            (ViewMode::Scene, _, _) | (_, None, _) => {
                textures.frame.or(textures.view.as_ref().map(uploaded))
            }
            (_, Some((t, _)), None) => Some(uploaded(t)),
        };
        if let Some((id, tsize, uv)) = shown {
            let scale = (avail.x / tsize.x).min(avail.y / tsize.y);
            let r = ui.add(
                egui::Image::new((id, tsize))
                    .uv(uv)
                    .fit_to_exact_size(tsize * scale.max(0.05))
                    .sense(Sense::click_and_drag()),
            );
            if r.dragged() {
                let d = r.drag_delta() * ppp;
                state.fly.look[0] += d.x;
                state.fly.look[1] += d.y;
            }
            if let (Some((_, caption)), None) = (&textures.aux, state.walkthrough)
                && state.view != ViewMode::Scene
            {
                let at = r.rect.left_bottom() + Vec2::new(8.0, -8.0);
                let font = egui::FontId::proportional(14.0);
                let galley = ui
                    .painter()
                    .layout_no_wrap(caption.clone(), font, Color32::WHITE);
                let bg = Rect::from_min_size(
                    at - Vec2::new(4.0, galley.size().y + 4.0),
                    galley.size() + Vec2::splat(8.0),
                );
                ui.painter()
                    .rect_filled(bg, 3.0, Color32::from_black_alpha(170));
                ui.painter()
                    .galley(at - Vec2::new(0.0, galley.size().y), galley, Color32::WHITE);
            }
        }
    });
    if state.show_timings
        && let Some(f) = frame
    {
        egui::Window::new("timings")
            .default_pos(Pos2::new(ctx.content_rect().right() - 330.0, 10.0))
            .resizable(false)
            .show(&ctx, |ui| timings(ui, state, f));
    }
    if let Some(k) = state.walkthrough
        && let Some(f) = frame
        && let Some(step) = f.steps.get(k)
    {
        let e = walkthrough::explain(step, &state.options, walkthrough::Executed::of(f, step));
        egui::Window::new("walkthrough")
            .default_pos(Pos2::new(360.0, ctx.content_rect().bottom() - 220.0))
            .default_width(520.0)
            .show(&ctx, |ui| {
                ui.heading(format!("{} / {}: {}", k + 1, state.steps.len(), e.title));
                ui.label(e.what);
                ui.label(egui::RichText::new(e.gl_state).monospace().small());
                ui.label("Page Up / Page Down to step, F7 to leave");
            });
    }
    if state.live_error.on {
        egui::Window::new("live error (sampled reference)")
            .default_pos(Pos2::new(10.0, ctx.content_rect().bottom() - 200.0))
            .show(&ctx, |ui| live_error(ui, state));
    }
    if state.view == ViewMode::Error {
        egui::Window::new("error against the exact reference")
            .default_pos(Pos2::new(360.0, ctx.content_rect().bottom() - 120.0))
            .show(&ctx, |ui| match (&state.error_job, state.current_error()) {
                (_, Some(r)) => {
                    let rates = r.total.rates();
                    ui.label(format!(
                        "error {:.3}% of {} receiver pixels: false shadow {:.3}% (red), false lit {:.3}% (blue)",
                        100.0 * rates.total,
                        rates.receiver_pixels,
                        100.0 * rates.false_shadow,
                        100.0 * rates.false_lit
                    ));
                }
                (Some(job), None) => {
                    ui.add(
                        egui::ProgressBar::new(job.progress())
                            .text("tracing shadow rays")
                            .show_percentage(),
                    );
                }
                (None, None) => {
                    ui.label("rendering masks…");
                }
            });
    }
    if state.show_help {
        egui::Window::new("keys")
            .anchor(egui::Align2::CENTER_CENTER, Vec2::ZERO)
            .collapsible(false)
            .show(&ctx, |ui| {
                egui::Grid::new("help").striped(true).show(ui, |ui| {
                    for (k, what) in HELP {
                        ui.label(egui::RichText::new(*k).strong());
                        ui.label(*what);
                        ui.end_row();
                    }
                });
            });
    }
    size
}
