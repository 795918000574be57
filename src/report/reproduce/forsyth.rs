//! Forsyth's slides and Vector's text: ID and priority buffers, second-depth (back-face) maps,
//! multiple frusta, the "Shadow Shootout" table, and the light-volume subdivision as a second
//! exact reference.
//! Each section quotes the claim and sets the measurement beside it.

use super::lab::{Lab, pct};
use super::{ReproduceError, Section};
use crate::report::bench::BenchRow;
use crate::report::table::{Align, Table};
use crate::truth::subdivision::{self, CacheWrite, Geometry, subdivision_mask};
use crate::truth::{Counts, Reference, Tracing, compare, reference_mask};
use std::time::Instant;

/// Units of progress this module reports (one per section).
pub const SECTIONS: usize = 6;

fn ms(x: f64) -> String {
    format!("{x:.1}")
}

/// The error columns every table here shares.
fn error_cells(r: &BenchRow) -> Vec<String> {
    vec![
        pct(r.error.total),
        pct(r.error.false_shadow),
        pct(r.error.false_lit),
        pct(r.error.total_excl_boundary),
    ]
}

const ERROR_HEADER: [(&str, Align); 4] = [
    ("error", Align::Right),
    ("false shadow", Align::Right),
    ("false lit", Align::Right),
    ("error outside the band", Align::Right),
];

/// A table of measured configurations: the name (under `first`), the error columns and the
/// frame time; each configuration's render command goes to the section's regenerate list.
fn error_table(
    lab: &Lab,
    s: &mut Section,
    first: &str,
    configs: &[(&str, Vec<&str>)],
    rows: &[BenchRow],
) -> Table {
    let mut header = vec![(first, Align::Left)];
    header.extend(ERROR_HEADER);
    header.push(("frame ms", Align::Right));
    let mut t = Table::new(&header);
    for ((name, sets), r) in configs.iter().zip(rows) {
        let mut row = vec![name.to_string()];
        row.extend(error_cells(r));
        row.push(ms(r.frame_ms.median));
        t.push(row);
        s.regenerate.push(lab.render_command(sets));
    }
    t
}

/// ID and priority buffers against depth maps on the grazing-light hard case (lab of
/// `assets/hard/grazing.toml`): the bias each needs, acne, the edge filter's shrink.
pub fn buffers(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "forsyth-buffers",
        "ID and priority buffers (Forsyth)",
        "Forsyth's slides: an ID buffer stores the nearest object's ID instead of its depth and \
         needs no bias; its \"edge acne\" where two IDs meet is cured by also accepting the \
         texels around (which shrinks shadows by a texel). Priority buffers store IDs sorted by \
         depth; the hybrid of priority and depth gives each object a range of depths, so its \
         bias is per object and nothing peter-pans between objects. Measured on the grazing \
         hard case (light 1-5 degrees over the floor), where a depth map without offset is \
         mostly acne.",
    );
    let configs: Vec<(&str, Vec<&str>)> = vec![
        ("depth, offset (1.1, 4)", vec!["shadow_map.buffer=depth"]),
        (
            "depth, no offset",
            vec!["shadow_map.buffer=depth", "shadow_map.offset=false"],
        ),
        ("id (parts), no offset", vec!["shadow_map.buffer=id"]),
        (
            "id (parts), edge filter",
            vec!["shadow_map.buffer=id", "shadow_map.id_edge_filter=true"],
        ),
        ("priority (parts)", vec!["shadow_map.buffer=priority"]),
        (
            "priority and depth (parts)",
            vec!["shadow_map.buffer=priority_depth"],
        ),
        (
            "second depth (back faces)",
            vec![
                "shadow_map.buffer=depth",
                "shadow_map.cull=back",
                "shadow_map.offset=false",
            ],
        ),
    ];
    let configs: Vec<(&str, Vec<&str>)> = configs
        .into_iter()
        .map(|(n, mut sets)| {
            sets.insert(0, "technique=shadow_map");
            (n, sets)
        })
        .collect();
    let rows = lab.measure(&configs)?;
    let t = error_table(lab, &mut s, "buffer", &configs, &rows);
    let e = |i: usize| rows[i].error.total;
    for (key, i) in [
        ("depth_offset", 0),
        ("depth_no_offset", 1),
        ("id", 2),
        ("id_filtered", 3),
        ("priority", 4),
        ("priority_depth", 5),
        ("second_depth", 6),
    ] {
        s.numbers.insert(key.into(), e(i));
    }
    s.findings.push(format!(
        "Without bias the depth map gets {} of the receivers wrong (offset (1.1, 4): {}); the ID \
         buffer, which has no bias at all, {}; with the edge filter {} (false lit {} against {}: \
         the shrink).",
        pct(e(1)),
        pct(e(0)),
        pct(e(2)),
        pct(e(3)),
        pct(rows[3].error.false_lit),
        pct(rows[2].error.false_lit),
    ));
    s.findings.push(format!(
        "The priority buffer gets {}, priority and depth {} (bias 0.02 of each part's own range; \
         at 1-5 degrees a texel spans more of the floor than that: acne within the part). The \
         back-face map (Wang & Molnar's second depth on closed casters) {} without offset.",
        pct(e(4)),
        pct(e(5)),
        pct(e(6)),
    ));
    s.tables.push(t);
    Ok(s)
}

/// Multiple frusta against one 90° face per direction at an equal texel budget, on the
/// duelling-frusta hard case with an omni light (lab of `assets/hard/duelling_omni.toml`).
pub fn frusta(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "forsyth-frusta",
        "Multiple frusta (Forsyth)",
        "Forsyth's slides: per light, choose shadow-buffer frusta around the objects in view \
         (base angle at most about 120 degrees), each the smallest buffer that gives its objects \
         the texels per metre their size on screen needs; large or close objects go into \
         several. Here each frustum is a rectangle of a cube face (at most 90 degrees) fitted \
         to the receivers in view, and all of a light's maps together hold the texels of six \
         faces of shadow_map.size (docs/frusta.md). Measured where the camera faces the omni \
         light: the shadows near the camera lie far from it, where a face spreads its texels \
         thinnest.",
    );
    let configs: Vec<(String, Vec<String>)> = [256, 512]
        .iter()
        .flat_map(|size| {
            ["six_spots", "frusta"].map(|omni| {
                (
                    format!("{omni}, {size}"),
                    vec![
                        "technique=shadow_map".to_string(),
                        format!("shadow_map.omni={omni}"),
                        format!("shadow_map.size={size}"),
                    ],
                )
            })
        })
        .collect();
    let borrowed: Vec<(&str, Vec<&str>)> = configs
        .iter()
        .map(|(n, sets)| (n.as_str(), sets.iter().map(String::as_str).collect()))
        .collect();
    let rows = lab.measure(&borrowed)?;
    let t = error_table(lab, &mut s, "omni light, map size", &borrowed, &rows);
    let e = |i: usize| rows[i].error.total;
    for (key, i) in [
        ("faces_256", 0),
        ("frusta_256", 1),
        ("faces_512", 2),
        ("frusta_512", 3),
    ] {
        s.numbers.insert(key.into(), e(i));
    }
    s.findings.push(format!(
        "At the same texels the frusta get {} of the receivers wrong against the faces' {} at \
         256, {} against {} at 512, for {:.1}x and {:.1}x the frame time (each frustum is one \
         more depth pass and lit pass). tests/frusta.rs holds the claim on the built-in scene \
         and along oa_dm1's flythrough too.",
        pct(e(1)),
        pct(e(0)),
        pct(e(3)),
        pct(e(2)),
        rows[1].frame_ms.median / rows[0].frame_ms.median.max(1e-9),
        rows[3].frame_ms.median / rows[2].frame_ms.median.max(1e-9),
    ));
    s.tables.push(t);
    Ok(s)
}

/// Mipmapped priority buffers under minification, against what most of each pixel's area sees,
/// on the hard case of stripes finer than a pixel (lab of `assets/hard/minified_grate.toml`).
pub fn priority_mips(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "forsyth-priority-mips",
        "Mipmapped priority buffers (Forsyth)",
        "Forsyth's slides: unlike depths, priorities can be filtered and mipmapped. Here each \
         level keeps a median of the four ranks below it (a vote: a mean of ranks is no rank) \
         and the lit pass reads the level of the pixel's footprint (docs/id-buffers.md). \
         Measured where a map is minified: bar shadows of a quarter of each 4-unit period, five \
         periods to a pixel at 160x120, against the exact masks at 1280x960 taken by majority \
         over each pixel's 8x8 block (ties left out).",
    );
    // The reference: the exact masks eight times finer, by majority.
    let (w, h, factor) = (160u32, 120u32, 8u32);
    let fine = lab.capture(&[
        &format!("width={}", w * factor),
        &format!("height={}", h * factor),
    ])?;
    let configs: Vec<(&str, Vec<String>)> = [("unfiltered", false), ("mipmapped", true)]
        .into_iter()
        .map(|(name, mipmap)| {
            (
                name,
                vec![
                    "technique=shadow_map".to_string(),
                    "shadow_map.buffer=priority".to_string(),
                    "shadow_map.size=2048".to_string(),
                    format!("shadow_map.priority_mipmap={mipmap}"),
                    format!("width={w}"),
                    format!("height={h}"),
                ],
            )
        })
        .collect();
    let mut t = Table::new(&[
        ("priority buffer, 2048", Align::Left),
        ("error against the majority", Align::Right),
        ("error against the pixel centres", Align::Right),
    ]);
    let mut errors = Vec::new();
    for (name, sets) in &configs {
        let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
        let c = lab.capture(&sets)?;
        let mut area = Counts::default();
        for (mask, exact) in c.frame.masks.iter().zip(&fine.exact) {
            area.add(&crate::truth::compare_majority(mask, exact, factor));
        }
        let e = area.rates().total;
        t.push(vec![name.to_string(), pct(e), pct(c.total.rates().total)]);
        s.numbers.insert(name.to_string(), e);
        s.regenerate.push(lab.render_command(&sets));
        errors.push(e);
    }
    s.regenerate
        .push("cargo test --release --test id_buffers mipmapped -- --nocapture".into());
    s.findings.push(format!(
        "Against what most of each pixel sees, the unfiltered buffer gets {} of the receivers \
         wrong (a stripe under the pixel's centre about one time in four) and the mip chain {}. \
         Where shadows are not minified (edges only: the thin casters, the grazing light, the \
         built-in scene) the chain does not help: a level's texels are aligned to the map, not \
         to the pixel, and move an edge by up to a texel of their level (the test prints those \
         cases).",
        pct(errors[0]),
        pct(errors[1]),
    ));
    s.tables.push(t);
    Ok(s)
}

/// IDs per surface, convex part and triangle, at 8, 16 and 32 bits, on the lab's scene.
pub fn ids(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "forsyth-ids",
        "What an ID stands for (Forsyth)",
        "Forsyth's slides: IDs per object cannot shadow the object itself; IDs per convex \
         sub-object can (a convex piece cannot shadow itself) but need pre-processing; IDs per \
         triangle need more than 8 bits. Here the convex parts are a greedy decomposition of \
         each caster group over shared edges (`shadow::parts`).",
    );
    let mut configs: Vec<(String, Vec<String>)> = Vec::new();
    let units: &[&str] = if lab.quick {
        &["part", "triangle"]
    } else {
        &["surface", "part", "triangle"]
    };
    for unit in units {
        configs.push((
            format!("{unit}, 32 bits"),
            vec![format!("shadow_map.id_unit={unit}")],
        ));
    }
    for bits in [8, 16] {
        configs.push((
            format!("triangle, {bits} bits"),
            vec![
                "shadow_map.id_unit=triangle".into(),
                format!("shadow_map.id_bits={bits}"),
            ],
        ));
    }
    configs.push((
        "part, edge filter".into(),
        vec![
            "shadow_map.id_unit=part".into(),
            "shadow_map.id_edge_filter=true".into(),
        ],
    ));
    let owned: Vec<(String, Vec<String>)> = configs
        .into_iter()
        .map(|(n, mut sets)| {
            sets.insert(0, "technique=shadow_map".into());
            sets.insert(1, "shadow_map.buffer=id".into());
            (n, sets)
        })
        .collect();
    let borrowed: Vec<(&str, Vec<&str>)> = owned
        .iter()
        .map(|(n, sets)| (n.as_str(), sets.iter().map(String::as_str).collect()))
        .collect();
    let rows = lab.measure(&borrowed)?;
    let mut header = vec![("IDs", Align::Left)];
    header.extend(ERROR_HEADER);
    let mut t = Table::new(&header);
    for ((name, sets), r) in borrowed.iter().zip(&rows) {
        let mut row = vec![name.to_string()];
        row.extend(error_cells(r));
        t.push(row);
        s.regenerate.push(lab.render_command(sets));
        s.numbers
            .insert(name.replace([' ', ','], "_"), r.error.total);
    }
    let (ids, parts) = crate::shadow::parts::convex_parts(lab.scene);
    s.findings.push(format!(
        "{}: {} triangles make {} convex parts. Errors by ID: {}.",
        lab.name,
        ids.len(),
        parts,
        borrowed
            .iter()
            .zip(&rows)
            .map(|((n, _), r)| format!("{n} {}", pct(r.error.total)))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    s.tables.push(t);
    Ok(s)
}

/// Forsyth's "Shadow Shootout" on the lab's scene, filled with measured numbers: per method,
/// fill (the lit and stencil passes' time), geometry (the shadow passes' time and volume
/// quads), aliasing (error in the boundary band), acne (false shadow away from it) and leaks.
pub fn shootout(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "forsyth-shootout",
        "The shadow shootout (Forsyth)",
        "Forsyth's \"Shadow Shootout\" compares the methods by fill rate, geometry, aliasing, \
         self-shadowing and what they need from the scene. Each column here is measured on \
         the same frame: fill = milliseconds of the lit and stencil passes, geometry = the \
         shadow maps' or volumes' drawing (and the volumes' side quads) or the subdivision \
         made current (its key checked, rebuilt where the light's geometry moved), aliasing = what the \
         pixels within a pixel of a shadow edge add to the error, acne = false shadow, leaks \
         = false lit.",
    );
    let mut configs: Vec<(&str, Vec<&str>)> = vec![
        ("depth map", vec!["technique=shadow_map"]),
        (
            "ID buffer",
            vec!["technique=shadow_map", "shadow_map.buffer=id"],
        ),
        (
            "priority buffer",
            vec!["technique=shadow_map", "shadow_map.buffer=priority"],
        ),
        (
            "priority and depth",
            vec!["technique=shadow_map", "shadow_map.buffer=priority_depth"],
        ),
        (
            "second depth (back faces)",
            vec!["technique=shadow_map", "shadow_map.cull=back"],
        ),
        ("shadow volumes", vec!["technique=shadow_volume"]),
        ("light-volume subdivision", vec!["technique=subdivision"]),
    ];
    if !lab.quick {
        configs.extend([
            ("perspective map", vec!["technique=psm"]),
            ("trapezoidal map", vec!["technique=tsm"]),
            ("hybrid (Chan & Durand)", vec!["technique=hybrid"]),
        ]);
    }
    let rows = lab.measure(&configs)?;
    let mut t = Table::new(&[
        ("method", Align::Left),
        ("frame ms", Align::Right),
        ("x shadows off", Align::Right),
        ("fill ms", Align::Right),
        ("geometry ms", Align::Right),
        ("volume quads", Align::Right),
        ("aliasing", Align::Right),
        ("acne", Align::Right),
        ("leaks", Align::Right),
        ("error", Align::Right),
    ]);
    for ((name, sets), r) in configs.iter().zip(&rows) {
        let pass = |k: &str| r.pass_ms.get(k).copied().unwrap_or(0.0);
        let fill = [
            "lights.lit",
            "lights.stencil",
            "lights.fill",
            "lights.classify",
        ]
        .iter()
        .map(|k| pass(k))
        .sum::<f64>();
        let geometry = [
            "lights.shadow_map",
            "lights.depth_copy",
            "lights.volume_build",
            "lights.volume_pieces",
            "lights.subdivision",
        ]
        .iter()
        .map(|k| pass(k))
        .sum::<f64>();
        let quads: usize = r.volumes.iter().map(|v| v.quads).sum();
        let aliasing = (r.error.total - r.error.total_excl_boundary).max(0.0);
        t.push(vec![
            name.to_string(),
            ms(r.frame_ms.median),
            format!("{:.2}", r.ratio_to_shadows_off),
            ms(fill),
            ms(geometry),
            quads.to_string(),
            pct(aliasing),
            pct(r.error.false_shadow),
            pct(r.error.false_lit),
            pct(r.error.total),
        ]);
        s.regenerate.push(lab.render_command(sets));
        s.numbers
            .insert(format!("{}_error", name.replace(' ', "_")), r.error.total);
    }
    if let Some(best) = rows
        .iter()
        .zip(&configs)
        .min_by(|a, b| a.0.error.total.total_cmp(&b.0.error.total))
    {
        s.findings.push(format!(
            "{}: most accurate is {} ({}), at {} ms a frame ({:.2}x shadows off).",
            lab.name,
            best.1.0,
            pct(best.0.error.total),
            ms(best.0.frame_ms.median),
            best.0.ratio_to_shadows_off
        ));
    }
    s.findings.push(
        "Aliasing here is what the pixels within one pixel of an exact shadow edge add: the \
         error minus the error outside that band, in points of percent; acne and leaks are \
         the false shadow and false lit of all receivers."
            .into(),
    );
    s.tables.push(t);
    Ok(s)
}

/// Vector's light-volume subdivision on the lab's scene: build time and fragments per light,
/// its cached reading, and its agreement with the ray caster on the scene camera's frame.
pub fn subdivision(lab: &mut Lab) -> Result<Section, ReproduceError> {
    let mut s = Section::new(
        "vector-subdivision",
        "Light-volume subdivision (Vector)",
        "Vector's text: each polygon's light volume clips the polygons behind it into lit and \
         shadowed fragments, once for static lights and casters; afterwards the camera moves \
         for free, and the result is exact in object space (in the literature, Chin & \
         Feiner's shadow-volume BSP tree). Here it is a second exact reference, made without \
         rays, checked against the ray caster.",
    );
    let capture = lab.capture(&["technique=none"])?;
    let scene = lab.scene;
    let Some(g) = capture.frame.gbuffer.as_ref() else {
        return Ok(s);
    };
    let reference = Reference::build_with(scene, false);
    let mut t = Table::new(&[
        ("light", Align::Right),
        ("receivers", Align::Right),
        ("casters", Align::Right),
        ("lit fragments", Align::Right),
        ("shadowed fragments", Align::Right),
        ("build ms", Align::Right),
        ("read ms", Align::Right),
        ("receiver px", Align::Right),
        ("differ", Align::Right),
        ("differ outside the band", Align::Right),
    ]);
    // Its own folder: the report may be in the temporary folder too.
    let cache = std::env::temp_dir().join(format!(
        "shadowlab-subdivision-cache-{}",
        std::process::id()
    ));
    let mut total = Counts::default();
    let mut build_ms = 0.0;
    for (l, light) in scene.lights.iter().enumerate() {
        let built = subdivision::subdivide_cached(
            scene,
            l,
            Geometry::Everything,
            (&cache, CacheWrite::Write),
        )
        .map_err(|e| ReproduceError::Plot(e.to_string()))?;
        let start = Instant::now();
        let read = subdivision::subdivide_cached(
            scene,
            l,
            Geometry::Everything,
            (&cache, CacheWrite::Write),
        )
        .map_err(|e| ReproduceError::Plot(e.to_string()))?;
        let read_ms = start.elapsed().as_secs_f64() * 1e3;
        let mask = subdivision_mask(&read, g, light);
        let exact = reference_mask(&reference, g, light, l, Tracing::Bvh);
        let c = compare(&mask, &exact);
        total.add(&c);
        let st = built.stats;
        build_ms += st.build.as_secs_f64() * 1e3;
        t.push(vec![
            l.to_string(),
            st.receivers.to_string(),
            st.casters.to_string(),
            st.lit_fragments.to_string(),
            st.shadowed_fragments.to_string(),
            ms(st.build.as_secs_f64() * 1e3),
            ms(read_ms),
            c.receiver_pixels.to_string(),
            (c.false_shadow + c.false_lit).to_string(),
            (c.false_shadow_excl_boundary + c.false_lit_excl_boundary).to_string(),
        ]);
    }
    let _ = std::fs::remove_dir_all(&cache);
    let r = total.rates();
    s.numbers.insert("disagreement".into(), r.total);
    s.numbers
        .insert("disagreement_excl_boundary".into(), r.total_excl_boundary);
    s.numbers.insert("build_ms".into(), build_ms);
    s.findings.push(format!(
        "{}: {} lights subdivided in {:.0} ms in all; against the ray caster the two exact \
         answers differ on {} of {} receiver pixels ({} outside the boundary band, where the ray \
         caster's lift off the surface decides grazing rays: tests/subdivision.rs).",
        lab.name,
        scene.lights.len(),
        build_ms,
        total.false_shadow + total.false_lit,
        total.receiver_pixels,
        pct(r.total_excl_boundary),
    ));
    s.regenerate.push(format!(
        "shadowlab subdivide --scene assets/scenes/{}.toml",
        lab.name
    ));
    s.tables.push(t);
    Ok(s)
}
