//! Light-volume subdivision (Vector's text; in the literature Chin & Feiner's shadow-volume BSP
//! tree): each casting triangle's light volume — the region behind it as seen from the light —
//! clips the triangles behind it into lit and shadowed fragments, in object space and f64. Done
//! once per static light, the result answers every camera: a surface point is shadowed exactly
//! when it lies on a shadowed fragment.
//!
//! This is the second exact reference, made a different way from the ray caster
//! (`reference.rs`): no rays, no per-pixel work beyond finding the fragment under a pixel. The
//! two agree to within the 1-pixel boundary band (`tests/subdivision.rs`).
//!
//! Order: Chin & Feiner sort the polygons front to back from the light and filter each through
//! a BSP tree of the volumes in front of it. Here each receiver triangle is clipped by every
//! volume that can reach it, found through a BVH of the casters' boxes; a volume only clips
//! what lies beyond its triangle's plane, so no order is needed, and the answer is the same
//! union of volumes. Alpha-tested texels are not modelled: casters are solid, as in
//! `Reference::build_with(scene, false)`.

use crate::images::{GBuffer, Mask};
use crate::scene::{Light, Scene, SurfaceOwner};
use bvh::aabb::{Aabb, Bounded};
use bvh::bounding_hierarchy::BHShape;
use bvh::bvh::Bvh;
use bvh::ray::Ray;
use glam::{DVec3, Vec3};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Distance (world units) within which a point counts as on a clipping plane. Far below the
/// reference's ray lift (0.01 units) and far above f64 rounding at Quake 3 scale (~1e-12).
const PLANE_EPSILON: f64 = 1e-7;

/// Most fragments one light may produce: a bound on memory for hostile scenes.
pub const MAX_FRAGMENTS: usize = 20_000_000;

/// Version of the on-disk format (bumped when the algorithm's answer changes).
const CACHE_VERSION: u32 = 1;

#[derive(Debug, thiserror::Error)]
pub enum SubdivisionError {
    #[error("light {light}: more than {MAX_FRAGMENTS} fragments")]
    TooManyFragments { light: usize },
    #[error("light {0} does not exist")]
    NoSuchLight(usize),
    #[error("subdivision cache {path}: {source}")]
    Cache {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// A convex planar polygon of a receiver triangle, wholly lit or wholly shadowed.
#[derive(Debug, Clone, PartialEq)]
pub struct Fragment {
    /// Index into `Scene::surfaces` of the triangle it was cut from.
    pub surface: u32,
    pub shadowed: bool,
    /// Corners in order around the polygon (at least three).
    pub points: Vec<DVec3>,
    node: usize,
}

impl Bounded<f64, 3> for Fragment {
    fn aabb(&self) -> Aabb<f64, 3> {
        let (min, max) = bounds(&self.points);
        let pad = 1e-3;
        Aabb::with_bounds(
            Point3::new(min.x - pad, min.y - pad, min.z - pad),
            Point3::new(max.x + pad, max.y + pad, max.z + pad),
        )
    }
}

impl BHShape<f64, 3> for Fragment {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}

/// What one light's subdivision made and what it cost.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SubdivisionStats {
    /// Triangles within the light's range that were clipped.
    pub receivers: usize,
    /// Casting triangles within the light's range.
    pub casters: usize,
    pub lit_fragments: usize,
    pub shadowed_fragments: usize,
    /// Volumes that clipped at least one receiver (a caster, receiver pair).
    pub clips: usize,
    /// Time to subdivide (zero when read from the cache).
    pub build: Duration,
    /// Whether it came from the disk cache.
    pub cached: bool,
}

/// One light's receivers cut into lit and shadowed fragments, with a BVH of the shadowed ones
/// for looking points up.
pub struct LightSubdivision {
    pub light: usize,
    pub stats: SubdivisionStats,
    pub fragments: Vec<Fragment>,
    shadowed: Vec<Fragment>,
    bvh: Option<Bvh<f64, 3>>,
}

/// A world-space triangle of the scene with its surface.
#[derive(Debug, Clone)]
struct Triangle {
    v: [DVec3; 3],
    surface: u32,
    casts: bool,
    /// Its light volume (casters only).
    volume: Option<[Plane; 4]>,
    node: usize,
}

impl Bounded<f64, 3> for Triangle {
    fn aabb(&self) -> Aabb<f64, 3> {
        let (min, max) = bounds(&self.v);
        Aabb::with_bounds(
            Point3::new(min.x, min.y, min.z),
            Point3::new(max.x, max.y, max.z),
        )
    }
}

impl BHShape<f64, 3> for Triangle {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}

fn bounds(points: &[DVec3]) -> (DVec3, DVec3) {
    points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// A plane `n·x + d`, positive on its inside.
#[derive(Debug, Clone, Copy)]
struct Plane {
    n: DVec3,
    d: f64,
}

impl Plane {
    fn through(n: DVec3, p: DVec3) -> Option<Plane> {
        let len = n.length();
        (len > 0.0 && len.is_finite()).then(|| {
            let n = n / len;
            Plane { n, d: -n.dot(p) }
        })
    }
    fn distance(&self, p: DVec3) -> f64 {
        self.n.dot(p) + self.d
    }
}

/// The light volume of triangle `v` from `light`: inside all four planes is behind the
/// triangle and within its pyramid. None when the light lies in the triangle's plane (it casts
/// nothing, as a ray in the plane of a triangle misses it) or the triangle is degenerate.
fn light_volume(v: &[DVec3; 3], light: DVec3) -> Option<[Plane; 4]> {
    let mut behind = Plane::through((v[1] - v[0]).cross(v[2] - v[0]), v[0])?;
    let l = behind.distance(light);
    if l.abs() <= PLANE_EPSILON {
        return None;
    }
    if l > 0.0 {
        behind = Plane {
            n: -behind.n,
            d: -behind.d,
        };
    }
    let mut planes = [behind; 4];
    for k in 0..3 {
        let (a, b, c) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
        let mut side = Plane::through((a - light).cross(b - light), light)?;
        if side.distance(c) < 0.0 {
            side = Plane {
                n: -side.n,
                d: -side.d,
            };
        }
        planes[k + 1] = side;
    }
    Some(planes)
}

/// Splits convex `poly` by `plane` into (inside, outside); points within [`PLANE_EPSILON`]
/// count as outside, so a volume never claims a surface it only touches.
fn split(poly: &[DVec3], plane: &Plane) -> (Vec<DVec3>, Vec<DVec3>) {
    let dist: Vec<f64> = poly
        .iter()
        .map(|p| plane.distance(*p) - PLANE_EPSILON)
        .collect();
    if dist.iter().all(|d| *d > 0.0) {
        return (poly.to_vec(), Vec::new());
    }
    if dist.iter().all(|d| *d <= 0.0) {
        return (Vec::new(), poly.to_vec());
    }
    let (mut inside, mut outside) = (Vec::new(), Vec::new());
    for i in 0..poly.len() {
        let j = (i + 1) % poly.len();
        let (p, q, dp, dq) = (poly[i], poly[j], dist[i], dist[j]);
        if dp > 0.0 {
            inside.push(p);
        } else {
            outside.push(p);
        }
        if (dp > 0.0) != (dq > 0.0) {
            let x = p + (q - p) * (dp / (dp - dq));
            inside.push(x);
            outside.push(x);
        }
    }
    (inside, outside)
}

/// The sum of a polygon's fan cross products: along its normal, twice its area long.
fn area_normal(poly: &[DVec3]) -> DVec3 {
    (1..poly.len().saturating_sub(1))
        .map(|i| (poly[i] - poly[0]).cross(poly[i + 1] - poly[0]))
        .sum()
}

/// Whether the polygon has an area worth keeping (not a sliver left by splitting at a vertex).
fn has_area(poly: &[DVec3]) -> bool {
    poly.len() >= 3 && area_normal(poly).length() > 1e-12
}

/// Cuts the lit pieces of one receiver by one volume: the parts inside it become shadowed.
fn clip(
    lit: Vec<Vec<DVec3>>,
    volume: &[Plane; 4],
    shadowed: &mut Vec<Vec<DVec3>>,
) -> Vec<Vec<DVec3>> {
    let mut still_lit = Vec::with_capacity(lit.len());
    for poly in lit {
        // Pieces outside the volume are kept only if some part lies inside: a volume that
        // misses the polygon must not cut it (that would multiply fragments for nothing).
        let mut outside_pieces = Vec::new();
        let mut rest = poly.clone();
        for plane in volume {
            let (inside, outside) = split(&rest, plane);
            if has_area(&outside) {
                outside_pieces.push(outside);
            }
            rest = inside;
            if rest.is_empty() {
                break;
            }
        }
        if has_area(&rest) {
            shadowed.push(rest);
            still_lit.extend(outside_pieces);
        } else {
            still_lit.push(poly);
        }
    }
    still_lit
}

/// Which of the scene's triangles a subdivision cuts and casts with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Geometry {
    /// Every visible triangle: the exact reference.
    Everything,
    /// The world's (BSP and scene-file meshes), not the models': what stays still, so that a
    /// moving model does not make it again (`subdivision.models = volumes`).
    World,
}

/// The scene's triangles in world space within `light`'s range: receivers are visible
/// surfaces, casters those that also cast.
fn triangles_in_range(scene: &Scene, light: &Light, geometry: Geometry) -> Vec<Triangle> {
    let centre = light.position.as_dvec3();
    let radius = light.radius as f64;
    let mut out = Vec::new();
    for (surface, s) in scene.surfaces.iter().enumerate() {
        let m = &scene.materials[s.material];
        let model = matches!(s.owner, SurfaceOwner::Model(_));
        if !m.visible || (model && geometry == Geometry::World) {
            continue;
        }
        let transform = scene.surface_transform(s).as_dmat4();
        let range = s.first_index as usize..(s.first_index + s.index_count) as usize;
        for tri in scene.indices[range].chunks_exact(3) {
            let v = [0, 1, 2].map(|k| {
                transform.transform_point3(scene.vertices[tri[k] as usize].pos().as_dvec3())
            });
            if !v.iter().all(|p| p.is_finite()) {
                continue;
            }
            let (lo, hi) = bounds(&v);
            if centre.clamp(lo, hi).distance(centre) >= radius {
                continue;
            }
            out.push(Triangle {
                v,
                surface: surface as u32,
                casts: m.casts_shadows,
                volume: None,
                node: 0,
            });
        }
    }
    out
}

/// The box of the light and a receiver: every caster whose volume reaches the receiver
/// touches it.
fn reach_box(light: DVec3, v: &[DVec3; 3]) -> Aabb<f64, 3> {
    let (lo, hi) = bounds(&[light, v[0], v[1], v[2]]);
    Aabb::with_bounds(Point3::new(lo.x, lo.y, lo.z), Point3::new(hi.x, hi.y, hi.z))
}

/// One receiver's pieces after every volume that reaches it.
struct Cut {
    lit: Vec<Vec<DVec3>>,
    shadowed: Vec<Vec<DVec3>>,
    /// Volumes that shadowed some of it.
    clips: usize,
    surface: u32,
}

/// Subdivides every receiver in `light`'s range by the volumes of the casters in range.
pub fn subdivide(scene: &Scene, index: usize) -> Result<LightSubdivision, SubdivisionError> {
    subdivide_geometry(scene, index, Geometry::Everything)
}

/// [`subdivide`] over `geometry`'s triangles only.
pub fn subdivide_geometry(
    scene: &Scene,
    index: usize,
    geometry: Geometry,
) -> Result<LightSubdivision, SubdivisionError> {
    let light = scene
        .lights
        .get(index)
        .ok_or(SubdivisionError::NoSuchLight(index))?;
    subdivide_triangles(index, light, triangles_in_range(scene, light, geometry))
}

/// [`subdivide`] over `triangles`, those in `light`'s range.
fn subdivide_triangles(
    index: usize,
    light: &Light,
    triangles: Vec<Triangle>,
) -> Result<LightSubdivision, SubdivisionError> {
    let start = Instant::now();
    let at = light.position.as_dvec3();
    let mut casters: Vec<Triangle> = triangles
        .iter()
        .filter(|t| t.casts)
        .map(|t| Triangle {
            volume: light_volume(&t.v, at),
            ..t.clone()
        })
        .collect();
    let bvh = (!casters.is_empty()).then(|| Bvh::build(&mut casters));
    let per_receiver: Vec<Cut> = triangles
        .par_iter()
        .map(|r| {
            let mut lit = vec![r.v.to_vec()];
            let mut shadowed = Vec::new();
            let mut clips = 0;
            if let Some(bvh) = &bvh {
                let query = reach_box(at, &r.v);
                for c in bvh.traverse_iterator(&query, &casters) {
                    if lit.is_empty() {
                        break;
                    }
                    if c.v == r.v {
                        continue;
                    }
                    let Some(volume) = &c.volume else {
                        continue;
                    };
                    // Most candidates miss: the receiver wholly outside one of the planes.
                    if volume
                        .iter()
                        .any(|p| r.v.iter().all(|x| p.distance(*x) <= PLANE_EPSILON))
                    {
                        continue;
                    }
                    let before = shadowed.len();
                    lit = clip(lit, volume, &mut shadowed);
                    clips += (shadowed.len() > before) as usize;
                }
            }
            Cut {
                lit,
                shadowed,
                clips,
                surface: r.surface,
            }
        })
        .collect();
    let total: usize = per_receiver
        .iter()
        .map(|c| c.lit.len() + c.shadowed.len())
        .sum();
    if total > MAX_FRAGMENTS {
        return Err(SubdivisionError::TooManyFragments { light: index });
    }
    let mut stats = SubdivisionStats {
        receivers: triangles.len(),
        casters: casters.len(),
        ..SubdivisionStats::default()
    };
    let mut fragments = Vec::with_capacity(total);
    for Cut {
        lit,
        shadowed,
        clips,
        surface,
    } in per_receiver
    {
        stats.clips += clips;
        stats.lit_fragments += lit.len();
        stats.shadowed_fragments += shadowed.len();
        let make = |points, shadowed| Fragment {
            surface,
            shadowed,
            points,
            node: 0,
        };
        fragments.extend(lit.into_iter().map(|p| make(p, false)));
        fragments.extend(shadowed.into_iter().map(|p| make(p, true)));
    }
    stats.build = start.elapsed();
    Ok(LightSubdivision::new(index, stats, fragments))
}

impl LightSubdivision {
    fn new(light: usize, stats: SubdivisionStats, fragments: Vec<Fragment>) -> LightSubdivision {
        let mut shadowed: Vec<Fragment> =
            fragments.iter().filter(|f| f.shadowed).cloned().collect();
        let bvh = (!shadowed.is_empty()).then(|| Bvh::build(&mut shadowed));
        LightSubdivision {
            light,
            stats,
            fragments,
            shadowed,
            bvh,
        }
    }

    /// The shadowed fragments of the surfaces `keep` accepts as triangles to draw (each
    /// convex polygon a fan, in its triangle's winding), three corners each as homogeneous
    /// f32 points (w = 1): what `technique = subdivision` marks into the stencil.
    pub fn shadowed_triangles(&self, keep: impl Fn(u32) -> bool) -> Vec<[f32; 4]> {
        let kept = || self.shadowed.iter().filter(|f| keep(f.surface));
        let corners: usize = kept().map(|f| 3 * f.points.len().saturating_sub(2)).sum();
        let mut out = Vec::with_capacity(corners);
        let point = |p: DVec3| [p.x as f32, p.y as f32, p.z as f32, 1.0];
        for f in kept() {
            for i in 1..f.points.len().saturating_sub(1) {
                out.extend([f.points[0], f.points[i], f.points[i + 1]].map(point));
            }
        }
        out
    }

    /// Whether surface point `p` with normal `n` lies on a shadowed fragment: a short probe
    /// through the surface along its normal, as long as the reference's ray lift either side.
    pub fn shadowed(&self, p: Vec3, n: Vec3) -> bool {
        let Some(bvh) = &self.bvh else {
            return false;
        };
        let p = p.as_dvec3();
        let n = n.as_dvec3().normalize_or_zero();
        if n == DVec3::ZERO {
            return false;
        }
        let reach = 2.0 * super::reference::origin_offset(p);
        let from = p + n * reach;
        let ray = Ray::new(
            Point3::new(from.x, from.y, from.z),
            Vector3::new(-n.x, -n.y, -n.z),
        );
        bvh.traverse_iterator(&ray, &self.shadowed)
            .any(|f| probe_hits(from, -n, 2.0 * reach, &f.points))
    }
}

/// Whether the segment from `from` along unit `dir` for `length` crosses convex polygon `poly`.
fn probe_hits(from: DVec3, dir: DVec3, length: f64, poly: &[DVec3]) -> bool {
    let n = area_normal(poly);
    let denom = n.dot(dir);
    if denom == 0.0 {
        return false;
    }
    let t = n.dot(poly[0] - from) / denom;
    if !(0.0..=length).contains(&t) {
        return false;
    }
    let x = from + dir * t;
    // Inside a convex polygon: on the same side of every edge (edges inclusive).
    let scale = n.length();
    (0..poly.len()).all(|i| {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        (b - a).cross(x - a).dot(n) >= -1e-9 * scale * (b - a).length()
    })
}

/// The subdivision's mask of `light` (index `index`) over `gbuffer`: receivers as the ray
/// caster's masks count them, shadowed where a shadowed fragment lies under the pixel.
pub fn subdivision_mask(sub: &LightSubdivision, gbuffer: &GBuffer, light: &Light) -> Mask {
    super::masks::mask_by(gbuffer, light, sub.light, |p, n| sub.shadowed(p, n))
}

/// Where subdivisions are kept: `$XDG_CACHE_HOME/shadowlab/subdivision`, else
/// `~/.cache/shadowlab/subdivision`.
pub fn default_cache_dir() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("shadowlab").join("subdivision"))
}

/// A hash of everything a light's subdivision depends on: the light's position and range and
/// every triangle in range (FNV-1a over their bits).
fn content_key(light: &Light, triangles: &[Triangle]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325 ^ CACHE_VERSION as u64;
    let mut eat = |x: u64| {
        for b in x.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x100_0000_01b3);
        }
    };
    for c in light.position.to_array() {
        eat(c.to_bits() as u64);
    }
    eat(light.radius.to_bits() as u64);
    for t in triangles {
        for p in t.v {
            for c in p.to_array() {
                eat(c.to_bits());
            }
        }
        eat(((t.surface as u64) << 1) | t.casts as u64);
    }
    h
}

/// What light `index`'s subdivision of `scene`'s `geometry` depends on, as the key its cache
/// file is named by: equal keys, equal fragments.
pub fn content_key_of(
    scene: &Scene,
    index: usize,
    geometry: Geometry,
) -> Result<u64, SubdivisionError> {
    let light = scene
        .lights
        .get(index)
        .ok_or(SubdivisionError::NoSuchLight(index))?;
    Ok(content_key(
        light,
        &triangles_in_range(scene, light, geometry),
    ))
}

/// The cache file of light `index` of `scene`, named by map and light and keyed by content.
fn cache_path(dir: &Path, scene: &Scene, index: usize, key: u64) -> PathBuf {
    let map: String = scene
        .name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    dir.join(format!("{map}-light{index}-{key:016x}.bin"))
}

/// Most bytes the cache directory holds: after a write, the files read or written longest ago
/// go first. Each pose of a moving light or model is a file of its own (oa_dm1: about 4 MB a
/// light), so without a bound benchmarks along moving paths filled 15 GB.
pub const CACHE_BUDGET_BYTES: u64 = 2 << 30;

/// Whether [`subdivide_cached`] writes what it builds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CacheWrite {
    /// Written, for the next run (a static light).
    Write,
    /// Only read (a light that moved: its next pose needs a new file, and this one would be
    /// read again only if the motion came back to it).
    ReadOnly,
}

/// [`subdivide_geometry`], read from `dir` when it holds this light's subdivision of the same
/// triangles, else built (and with [`CacheWrite::Write`] written there, the directory then
/// kept within [`CACHE_BUDGET_BYTES`]).
pub fn subdivide_cached(
    scene: &Scene,
    index: usize,
    geometry: Geometry,
    (dir, write): (&Path, CacheWrite),
) -> Result<LightSubdivision, SubdivisionError> {
    let light = scene
        .lights
        .get(index)
        .ok_or(SubdivisionError::NoSuchLight(index))?;
    let triangles = triangles_in_range(scene, light, geometry);
    let path = cache_path(dir, scene, index, content_key(light, &triangles));
    if let Ok(bytes) = std::fs::read(&path)
        && let Some(fragments) = decode(&bytes)
        && fits(&fragments, scene.surfaces.len())
    {
        let (lit, shadowed) =
            fragments.iter().fold(
                (0, 0),
                |(l, s), f| {
                    if f.shadowed { (l, s + 1) } else { (l + 1, s) }
                },
            );
        let stats = SubdivisionStats {
            lit_fragments: lit,
            shadowed_fragments: shadowed,
            cached: true,
            ..SubdivisionStats::default()
        };
        // Read now: the last file the budget evicts (a failure only makes it older).
        if let Ok(f) = std::fs::File::options().append(true).open(&path) {
            let _ = f.set_modified(std::time::SystemTime::now());
        }
        return Ok(LightSubdivision::new(index, stats, fragments));
    }
    let sub = subdivide_triangles(index, light, triangles)?;
    if write == CacheWrite::ReadOnly {
        return Ok(sub);
    }
    let io = |source| SubdivisionError::Cache {
        path: path.clone(),
        source,
    };
    std::fs::create_dir_all(dir).map_err(io)?;
    // Written aside and renamed, so a reader never sees half a file.
    let partial = path.with_extension("partial");
    std::fs::write(&partial, encode(&sub.fragments)).map_err(io)?;
    std::fs::rename(&partial, &path).map_err(io)?;
    prune(dir, &path, CACHE_BUDGET_BYTES).map_err(io)?;
    Ok(sub)
}

/// Deletes the cache files of `dir` read or written longest ago until the rest hold at most
/// `budget` bytes; `keep`, just written, stays.
fn prune(dir: &Path, keep: &Path, budget: u64) -> std::io::Result<()> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let path = entry.path();
        let meta = entry.metadata()?;
        if meta.is_file() && path.extension().is_some_and(|x| x == "bin") {
            files.push((meta.modified()?, meta.len(), path));
        }
    }
    let mut total: u64 = files.iter().map(|f| f.1).sum();
    files.sort();
    for (_, size, path) in files {
        if total <= budget {
            break;
        }
        if path != keep {
            std::fs::remove_file(&path)?;
            total -= size;
        }
    }
    Ok(())
}

const MAGIC: &[u8; 4] = b"SLSD";

fn encode(fragments: &[Fragment]) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&CACHE_VERSION.to_le_bytes());
    out.extend_from_slice(&(fragments.len() as u64).to_le_bytes());
    for f in fragments {
        out.extend_from_slice(&f.surface.to_le_bytes());
        out.push(f.shadowed as u8);
        out.extend_from_slice(&(f.points.len() as u32).to_le_bytes());
        for p in &f.points {
            for c in p.to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    out
}

/// Reads what [`encode`] wrote; None for anything else (a stale or damaged file is rebuilt).
/// Whether decoded fragments can be this scene's: each names one of its `surfaces` and has
/// finite corners (a file that only looks whole is built again, not trusted).
fn fits(fragments: &[Fragment], surfaces: usize) -> bool {
    fragments
        .iter()
        .all(|f| (f.surface as usize) < surfaces && f.points.iter().all(|p| p.is_finite()))
}

fn decode(bytes: &[u8]) -> Option<Vec<Fragment>> {
    let mut at = 0usize;
    let mut take = |n: usize| -> Option<&[u8]> {
        let s = bytes.get(at..at.checked_add(n)?)?;
        at += n;
        Some(s)
    };
    if take(4)? != MAGIC || u32::from_le_bytes(take(4)?.try_into().ok()?) != CACHE_VERSION {
        return None;
    }
    let count = u64::from_le_bytes(take(8)?.try_into().ok()?) as usize;
    // Each fragment takes at least 81 bytes: a count beyond the file is a damaged file.
    if count > bytes.len() / 81 {
        return None;
    }
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        let surface = u32::from_le_bytes(take(4)?.try_into().ok()?);
        let shadowed = take(1)?[0] != 0;
        let n = u32::from_le_bytes(take(4)?.try_into().ok()?) as usize;
        if !(3..=64).contains(&n) {
            return None;
        }
        let mut points = Vec::with_capacity(n);
        for _ in 0..n {
            let mut c = [0.0; 3];
            for x in &mut c {
                *x = f64::from_le_bytes(take(8)?.try_into().ok()?);
            }
            points.push(DVec3::from_array(c));
        }
        out.push(Fragment {
            surface,
            shadowed,
            points,
            node: 0,
        });
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cache_keeps_within_its_budget_dropping_the_oldest_first() {
        let dir = std::env::temp_dir().join(format!("shadowlab-prune-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let start = std::time::SystemTime::now() - Duration::from_secs(1000);
        let mut paths = Vec::new();
        for i in 0..5u64 {
            let p = dir.join(format!("map-light{i}-0.bin"));
            std::fs::write(&p, vec![0u8; 100]).unwrap();
            let f = std::fs::File::options().append(true).open(&p).unwrap();
            f.set_modified(start + Duration::from_secs(10 * i)).unwrap();
            paths.push(p);
        }
        // Another kind of file is not the cache's to delete.
        std::fs::write(dir.join("notes.txt"), vec![0u8; 1000]).unwrap();
        // The oldest is the one just written: it stays, the next oldest go.
        prune(&dir, &paths[0], 250).unwrap();
        let left: Vec<bool> = paths.iter().map(|p| p.exists()).collect();
        assert_eq!(left, [true, false, false, false, true]);
        assert!(dir.join("notes.txt").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn quad(z: f64, half: f64) -> Vec<DVec3> {
        vec![
            DVec3::new(-half, -half, z),
            DVec3::new(half, -half, z),
            DVec3::new(half, half, z),
            DVec3::new(-half, half, z),
        ]
    }

    fn area(poly: &[DVec3]) -> f64 {
        0.5 * area_normal(poly).length()
    }

    #[test]
    fn a_triangle_shadows_its_projection_exactly() {
        // Light at z = 10, caster triangle at z = 5, receiver floor at z = 0: the shadow is the
        // caster scaled by 2 about the light's foot.
        let light = DVec3::new(0.0, 0.0, 10.0);
        let caster = [
            DVec3::new(0.0, 0.0, 5.0),
            DVec3::new(1.0, 0.0, 5.0),
            DVec3::new(0.0, 1.0, 5.0),
        ];
        let volume = light_volume(&caster, light).unwrap();
        let mut shadowed = Vec::new();
        let lit = clip(vec![quad(0.0, 10.0)], &volume, &mut shadowed);
        let shadow_area: f64 = shadowed.iter().map(|p| area(p)).sum();
        let lit_area: f64 = lit.iter().map(|p| area(p)).sum();
        // Each of the four planes gives the volume PLANE_EPSILON: the area is short by about
        // its perimeter times 1e-7.
        assert!((shadow_area - 2.0).abs() < 1e-5, "{shadow_area}");
        assert!((lit_area + shadow_area - 400.0).abs() < 1e-9);
    }

    #[test]
    fn nothing_in_front_of_a_caster_is_shadowed() {
        let light = DVec3::new(0.0, 0.0, 10.0);
        let caster = [
            DVec3::new(-1.0, -1.0, 5.0),
            DVec3::new(1.0, -1.0, 5.0),
            DVec3::new(0.0, 1.0, 5.0),
        ];
        let volume = light_volume(&caster, light).unwrap();
        let mut shadowed = Vec::new();
        // Between the light and the caster, and coplanar with the caster.
        for z in [7.0, 5.0] {
            let lit = clip(vec![quad(z, 0.5)], &volume, &mut shadowed);
            assert_eq!(lit.len(), 1);
        }
        assert!(shadowed.is_empty());
    }

    #[test]
    fn a_light_in_the_casters_plane_casts_nothing() {
        let caster = [
            DVec3::new(0.0, 0.0, 5.0),
            DVec3::new(1.0, 0.0, 5.0),
            DVec3::new(0.0, 1.0, 5.0),
        ];
        assert!(light_volume(&caster, DVec3::new(3.0, 3.0, 5.0)).is_none());
    }

    #[test]
    fn the_cache_format_round_trips_and_refuses_damage() {
        let fragments = vec![Fragment {
            surface: 7,
            shadowed: true,
            points: quad(1.5, 2.0),
            node: 0,
        }];
        let bytes = encode(&fragments);
        let back = decode(&bytes).unwrap();
        assert_eq!(back[0].points, fragments[0].points);
        assert_eq!((back[0].surface, back[0].shadowed), (7, true));
        assert!(decode(&bytes[..bytes.len() - 1]).is_none());
        let mut huge = bytes.clone();
        huge[8..16].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(decode(&huge).is_none());
        // Whole, but not this scene's: a surface it lacks, a corner at infinity.
        assert!(fits(&back, 8) && !fits(&back, 7));
        let mut far = back.clone();
        far[0].points[1].x = f64::INFINITY;
        assert!(!fits(&far, 8));
    }

    #[test]
    fn the_probe_finds_a_point_on_a_polygon_and_misses_beside_it() {
        let poly = quad(0.0, 1.0);
        let down = DVec3::new(0.0, 0.0, -1.0);
        assert!(probe_hits(DVec3::new(0.5, 0.5, 0.1), down, 0.2, &poly));
        assert!(!probe_hits(DVec3::new(1.5, 0.5, 0.1), down, 0.2, &poly));
        assert!(!probe_hits(DVec3::new(0.5, 0.5, 0.5), down, 0.2, &poly));
    }
}
