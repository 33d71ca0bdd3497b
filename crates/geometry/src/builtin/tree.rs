//! `tree`: García et al.'s "Tree Scene" (García et al. 2003, sections 2.7
//! and 2.9): a procedurally grown tree on a ground of 0.02 × 0.02 squares,
//! 71 966 triangles in all, with a 500-triangle mobile ball that rolls around
//! the trunk, through the tree's shadow.
//!
//! - Ground: the square [-1, 1] × [-1, 1] at y = 0, one mesh of 100 × 100
//!   squares of 0.02 × 0.02, two triangles each (20 000 triangles, 101²
//!   shared vertices, flat normals +y).
//! - Tree: a trunk and recursive branches as tapered tubes with smooth
//!   normals, capped with a cone at the tip (mesh `branches`), and leaves as
//!   flat quads of 0.012 × 0.01 (two triangles each) in clusters around the
//!   twigs (mesh `leaves`); both meshes are object `tree`. The leaf count fills
//!   ground + tree up to exactly 71 966 triangles, the count of the paper's
//!   scene (section 2.9). Grown from a fixed seed with the module's own
//!   SplitMix64 generator, so every build is identical.
//! - Ball: a UV sphere of radius 0.07 (25 slices × 11 stacks = 500
//!   triangles, smooth normals), object `ball`, centred at the origin in its
//!   rest pose. Its path ([`ball_path`]) rolls it without slipping, 1 mm above
//!   the ground, on a circle of radius 0.49 = 7 ball radii round the trunk in
//!   8 s (64 keyframes, looping; the circle is 7 ball circumferences long, so
//!   the rolling closes exactly), starting on the light's side (left, behind)
//!   and crossing the shadow of the trunk and crown half-way (right, front).
//! - Light: a 0.5 × 0.5 emitting rectangle facing down, centred at
//!   (-0.9, 2.4, -0.3), up and to the left behind the tree, radiance
//!   (40, 38, 34) W/(m² sr): an area light, so that the Mitsuba reference
//!   sees the same emitter. The shadow falls to the right, slightly forward.
//! - Materials: all diffuse ("for Real Time purposes, we are using diffuse
//!   scenes", section 3.2.1).
//! - Camera at (0, 0.9, 2.7) looking at (0, 0.5, 0), vertical field of view 45°.

use std::f32::consts::{PI, TAU};

use glam::{Quat, Vec2, Vec3};

use crate::animation::{Keyframe, ObjectPath, PathEnd};
use crate::{Camera, Material, Mesh, Object, Rgb, Scene};

/// Half the side of the square ground, in metres (García et al. 2003, section 2.9).
pub const GROUND_HALF_SIZE: f32 = 1.0;
/// Side of a ground square: "triangles in the ground have a 0.02×0.02 size" (García et al. 2003, section 2.7).
pub const GROUND_CELL: f32 = 0.02;
/// Ground squares along each side (García et al. 2003, section 2.7).
pub const GROUND_CELLS: u32 = 100;
/// Triangles of the ground and the tree together: "a scene with 71966 triangles" (García et al. 2003, section 2.9).
pub const STATIC_TRIANGLES: usize = 71_966;
/// Length and width of a leaf quad: tree triangles are "around 0.01×0.01" (García et al. 2003, section 2.7).
pub const LEAF_SIZE: Vec2 = Vec2::new(0.012, 0.010);
/// Radius of the mobile ball (García et al. 2003, section 2.9).
pub const BALL_RADIUS: f32 = 0.07;
/// Longitudes of the ball's UV sphere (García et al. 2003, section 2.9: a 500-triangle mobile object).
pub const BALL_SLICES: u32 = 25;
/// Latitude bands of the ball's UV sphere, 500 triangles with [`BALL_SLICES`] (García et al. 2003, section 2.9).
pub const BALL_STACKS: u32 = 11;
/// Radius of the ball's circle round the trunk: a whole number of ball radii, so rolling closes (García et al. 2003, section 2.2.2).
pub const BALL_PATH_RADIUS: f32 = 7.0 * BALL_RADIUS;
/// Gap between the ball and the ground (García et al. 2003, section 2.2.2).
pub const BALL_CLEARANCE: f32 = 0.001;
/// Time the ball takes to go round once, in seconds (García et al. 2003, section 2.2.2).
pub const BALL_PATH_DURATION: f32 = 8.0;
/// Keyframes of the ball's path before the last, which repeats the first (García et al. 2003, section 2.2.2).
pub const BALL_PATH_KEYS: u32 = 64;
/// Centre of the light rectangle; light sources are static (García et al. 2003, section 2.2.2).
pub const LIGHT_CENTRE: Vec3 = Vec3::new(-0.9, 2.4, -0.3);
/// Side of the square light (García et al. 2003, section 2.2.2).
pub const LIGHT_SIZE: f32 = 0.5;
/// Radiance of the light, in W/(m² sr) (García et al. 2003, section 2.9).
pub const LIGHT_RADIANCE: Rgb = Rgb::new(40.0, 38.0, 34.0);
/// Reflectance of the diffuse ground (García et al. 2003, section 3.2.1).
pub const GROUND_REFLECTANCE: Rgb = Rgb::new(0.45, 0.42, 0.35);
/// Reflectance of the diffuse bark (García et al. 2003, section 3.2.1).
pub const BARK_REFLECTANCE: Rgb = Rgb::new(0.30, 0.20, 0.12);
/// Reflectance of the diffuse leaves (García et al. 2003, section 3.2.1).
pub const LEAF_REFLECTANCE: Rgb = Rgb::new(0.18, 0.40, 0.10);
/// Reflectance of the diffuse ball (García et al. 2003, section 3.2.1).
pub const BALL_REFLECTANCE: Rgb = Rgb::new(0.80, 0.15, 0.10);
/// Seed of the tree's generator.
const SEED: u64 = 0x07EE_5200_3007_1966;

/// `tree`: García et al.'s Tree Scene with its mobile ball posed at time 0 (sections 2.7 and 2.9).
pub fn tree() -> Scene {
    let mut rng = SplitMix64(SEED);
    let ground = ground_mesh(0);
    let skeleton = grow_tree(&mut rng);
    let branches = branch_mesh(&skeleton, 1);
    let leaf_count = STATIC_TRIANGLES
        .saturating_sub(ground.indices.len() + branches.indices.len())
        .max(2 * twigs(&skeleton))
        / 2;
    let leaves = leaf_mesh(&skeleton, leaf_count, &mut rng, 2);
    let ball = ball_mesh(3);
    let light = light_mesh(4);
    let meshes = vec![ground, branches, leaves, ball, light];
    let materials = vec![
        Material::diffuse("ground", GROUND_REFLECTANCE),
        Material::diffuse("bark", BARK_REFLECTANCE),
        Material::diffuse("leaf", LEAF_REFLECTANCE),
        Material::diffuse("ball", BALL_REFLECTANCE),
        Material::diffuse("light", Rgb::splat(0.8)).with_emission(LIGHT_RADIANCE),
    ];
    let object = |name: &str, meshes: Vec<u32>| Object {
        name: name.to_owned(),
        meshes,
        transform: glam::Affine3A::IDENTITY,
    };
    let objects = vec![
        object("ground", vec![0]),
        object("tree", vec![1, 2]),
        object("ball", vec![3]),
        object("light", vec![4]),
    ];
    let camera = Camera::look_at(
        Vec3::new(0.0, 0.9, 2.7),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::Y,
        45.0,
    );
    Scene::new("tree", meshes, materials, objects, Vec::new(), camera)
        .and_then(|scene| scene.with_mobile("ball", ball_path()))
        .expect("the built-in tree scene is valid")
}

/// The ball's path: rolling without slipping round the trunk, looping (García et al. 2003, section 2.2.2).
pub fn ball_path() -> ObjectPath {
    // The ball's centre is at angle φ0 + φ on the circle; the ball turns by
    // -φ about +y (following the circle) and rolls by (R / r) φ about the
    // horizontal axis y × v, v its starting velocity.
    let start = 1.1 * PI;
    let height = BALL_RADIUS + BALL_CLEARANCE;
    let velocity = Vec3::new(-start.sin(), 0.0, start.cos());
    let roll_axis = Vec3::Y.cross(velocity).normalize();
    let rolls = BALL_PATH_RADIUS / BALL_RADIUS;
    let key = |i: u32| {
        let phi = TAU * i as f32 / BALL_PATH_KEYS as f32;
        let angle = start + phi;
        Keyframe::new(
            BALL_PATH_DURATION * i as f32 / BALL_PATH_KEYS as f32,
            Vec3::new(
                BALL_PATH_RADIUS * angle.cos(),
                height,
                BALL_PATH_RADIUS * angle.sin(),
            ),
            Quat::from_rotation_y(-phi) * Quat::from_axis_angle(roll_axis, rolls * phi),
        )
    };
    let mut keys: Vec<Keyframe> = (0..BALL_PATH_KEYS).map(key).collect();
    // The last keyframe is the first, one period later: the loop is seamless.
    keys.push(Keyframe {
        time: BALL_PATH_DURATION,
        ..keys[0]
    });
    ObjectPath::new(keys, PathEnd::Loop).expect("the ball's path is valid")
}

/// A small deterministic generator (SplitMix64), so the tree needs no dependency.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in [lo, hi).
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform on the unit sphere.
    fn direction(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, TAU);
        let s = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

/// The ground: [`GROUND_CELLS`]² squares of [`GROUND_CELL`], two triangles each, facing +y.
fn ground_mesh(material: u32) -> Mesh {
    let n = GROUND_CELLS;
    let mut positions = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    let mut uvs = Vec::with_capacity(positions.capacity());
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            positions.push(Vec3::new(
                -GROUND_HALF_SIZE + i as f32 * GROUND_CELL,
                0.0,
                -GROUND_HALF_SIZE + j as f32 * GROUND_CELL,
            ));
            uvs.push(Vec2::new(u, v));
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let mut indices = Vec::with_capacity((2 * n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            indices.push([a, b, c]);
            indices.push([c, b, d]);
        }
    }
    Mesh {
        name: "ground".into(),
        normals: vec![Vec3::Y; positions.len()],
        positions,
        uvs,
        indices,
        material,
    }
}

/// One branch: its axis as a polyline with a radius at each point.
struct Branch {
    points: Vec<Vec3>,
    radii: Vec<f32>,
    level: usize,
}

impl Branch {
    /// Point and unit direction at `s` ∈ [0, 1] along the branch's length.
    fn along(&self, s: f32) -> (Vec3, Vec3, f32) {
        let n = self.points.len() - 1;
        let x = (s.clamp(0.0, 1.0) * n as f32).min(n as f32 - 1e-4);
        let i = x as usize;
        let f = x - i as f32;
        let (a, b) = (self.points[i], self.points[i + 1]);
        let radius = self.radii[i] + f * (self.radii[i + 1] - self.radii[i]);
        (a.lerp(b, f), (b - a).normalize(), radius)
    }
}

/// Growth rule of one level of branches.
struct Level {
    /// Sides of the tube.
    sides: u32,
    /// Distance between rings.
    ring_spacing: f32,
    /// Children grown from a branch of this level.
    children: u32,
    /// Where along the branch the children start.
    attach: (f32, f32),
}

/// Trunk, main branches, branches, small branches, twigs.
const LEVELS: [Level; 5] = [
    Level {
        sides: 12,
        ring_spacing: 0.03,
        children: 5,
        attach: (0.5, 1.0),
    },
    Level {
        sides: 8,
        ring_spacing: 0.025,
        children: 4,
        attach: (0.3, 1.0),
    },
    Level {
        sides: 6,
        ring_spacing: 0.02,
        children: 4,
        attach: (0.3, 1.0),
    },
    Level {
        sides: 4,
        ring_spacing: 0.018,
        children: 3,
        attach: (0.35, 1.0),
    },
    Level {
        sides: 4,
        ring_spacing: 0.016,
        children: 0,
        attach: (0.0, 0.0),
    },
];
/// Length of the trunk.
const TRUNK_LENGTH: f32 = 0.5;
/// Radius of the trunk at the ground.
const TRUNK_RADIUS: f32 = 0.035;
/// Radius of a twig's tip.
const TIP_RADIUS: f32 = 0.0012;

/// The tree's branches, trunk first; the twigs are those of the last level.
fn grow_tree(rng: &mut SplitMix64) -> Vec<Branch> {
    let mut out = Vec::new();
    grow(
        rng,
        &mut out,
        0,
        Vec3::ZERO,
        Vec3::Y,
        TRUNK_LENGTH,
        TRUNK_RADIUS,
    );
    out
}

/// Grows a branch of `level` from `base` along `direction`, then its children.
fn grow(
    rng: &mut SplitMix64,
    out: &mut Vec<Branch>,
    level: usize,
    base: Vec3,
    direction: Vec3,
    length: f32,
    radius: f32,
) {
    let rule = &LEVELS[level];
    let segments = (length / rule.ring_spacing).ceil().max(2.0) as usize;
    let end_radius = if rule.children == 0 {
        TIP_RADIUS
    } else {
        0.45 * radius
    };
    let mut points = vec![base];
    let mut radii = vec![radius];
    let mut dir = direction;
    let step = length / segments as f32;
    for i in 1..=segments {
        // A little wander, and a pull upwards; the trunk leaves the ground
        // straight, so that its base ring lies on the ground.
        let wander = if level == 0 { 0.02 } else { 0.12 };
        let pull = rng.direction() * wander + Vec3::Y * 0.03;
        if level > 0 || i > 1 {
            dir = (dir + pull).normalize();
        }
        points.push(points[i - 1] + dir * step);
        let s = i as f32 / segments as f32;
        radii.push(radius + (end_radius - radius) * s);
    }
    let branch = Branch {
        points,
        radii,
        level,
    };
    let children = rule.children;
    let mut phase = rng.range(0.0, TAU);
    let mut child_specs = Vec::new();
    for c in 0..children {
        // The last child continues the branch (a leader); the others spread
        // round it at the golden angle.
        let leader = c + 1 == children;
        let s = if leader {
            1.0
        } else {
            rule.attach.0
                + (rule.attach.1 - rule.attach.0) * (c as f32 + rng.range(0.2, 0.8))
                    / (children - 1) as f32
        };
        let (point, axis, parent_radius) = branch.along(s);
        let spread = if leader {
            rng.range(0.1, 0.3)
        } else {
            rng.range(0.6, 0.95)
        };
        phase += 2.39996 + rng.range(-0.3, 0.3);
        let side = perpendicular(axis);
        let side = Quat::from_axis_angle(axis, phase) * side;
        let mut child_dir = Quat::from_axis_angle(side.cross(axis).normalize(), spread) * axis;
        // Keep branches from drooping into the ground.
        if child_dir.y < 0.1 {
            child_dir = (child_dir + Vec3::Y * (0.1 - child_dir.y) * 2.0).normalize();
        }
        let child_length = length * if leader { 0.7 } else { rng.range(0.55, 0.7) };
        let child_radius = parent_radius * if leader { 0.85 } else { 0.7 };
        child_specs.push((point, child_dir, child_length, child_radius));
    }
    out.push(branch);
    for (point, child_dir, child_length, child_radius) in child_specs {
        grow(
            rng,
            out,
            level + 1,
            point,
            child_dir,
            child_length,
            child_radius,
        );
    }
}

/// A unit vector perpendicular to the unit vector `v`.
fn perpendicular(v: Vec3) -> Vec3 {
    let other = if v.x.abs() < 0.9 { Vec3::X } else { Vec3::Z };
    v.cross(other).normalize()
}

/// Number of twigs (branches of the last level).
fn twigs(skeleton: &[Branch]) -> usize {
    skeleton
        .iter()
        .filter(|b| b.level == LEVELS.len() - 1)
        .count()
}

/// All branches as tapered tubes with smooth normals, each closed by a cone at its tip.
fn branch_mesh(skeleton: &[Branch], material: u32) -> Mesh {
    let mut mesh = Mesh {
        name: "branches".into(),
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        indices: Vec::new(),
        material,
    };
    for branch in skeleton {
        let sides = LEVELS[branch.level].sides;
        let n = branch.points.len();
        // Parallel-transported frame along the axis.
        let tangent = |i: usize| {
            let (a, b) = (
                branch.points[i.saturating_sub(1)],
                branch.points[(i + 1).min(n - 1)],
            );
            (b - a).normalize()
        };
        let mut normal = perpendicular(tangent(0));
        let mut previous_tangent = tangent(0);
        let mut length = 0.0;
        for i in 0..n {
            let t = tangent(i);
            normal = Quat::from_rotation_arc(previous_tangent, t) * normal;
            normal = (normal - t * normal.dot(t)).normalize();
            previous_tangent = t;
            let binormal = t.cross(normal);
            if i > 0 {
                length += branch.points[i].distance(branch.points[i - 1]);
            }
            let (i0, i1) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let slope = (branch.radii[i0] - branch.radii[i1])
                / branch.points[i0].distance(branch.points[i1]);
            for k in 0..sides {
                let theta = TAU * k as f32 / sides as f32;
                let radial = normal * theta.cos() + binormal * theta.sin();
                mesh.positions
                    .push(branch.points[i] + radial * branch.radii[i]);
                mesh.normals.push((radial + t * slope).normalize());
                mesh.uvs.push(Vec2::new(k as f32 / sides as f32, length));
            }
        }
        let base = (mesh.positions.len() - n * sides as usize) as u32;
        let ring = |i: usize, k: u32| base + i as u32 * sides + k % sides;
        for i in 0..n - 1 {
            for k in 0..sides {
                let (a0, a1, b0, b1) = (
                    ring(i, k),
                    ring(i, k + 1),
                    ring(i + 1, k),
                    ring(i + 1, k + 1),
                );
                mesh.indices.push([a0, a1, b0]);
                mesh.indices.push([a1, b1, b0]);
            }
        }
        let tip_dir = tangent(n - 1);
        let apex = mesh.positions.len() as u32;
        mesh.positions
            .push(branch.points[n - 1] + tip_dir * branch.radii[n - 1]);
        mesh.normals.push(tip_dir);
        mesh.uvs.push(Vec2::new(0.5, length));
        for k in 0..sides {
            mesh.indices
                .push([ring(n - 1, k), ring(n - 1, k + 1), apex]);
        }
    }
    mesh
}

/// `count` flat leaf quads clustered round the twigs, facing mostly up.
fn leaf_mesh(skeleton: &[Branch], count: usize, rng: &mut SplitMix64, material: u32) -> Mesh {
    let twigs: Vec<&Branch> = skeleton
        .iter()
        .filter(|b| b.level == LEVELS.len() - 1)
        .collect();
    let mut mesh = Mesh {
        name: "leaves".into(),
        positions: Vec::with_capacity(4 * count),
        normals: Vec::with_capacity(4 * count),
        uvs: Vec::with_capacity(4 * count),
        indices: Vec::with_capacity(2 * count),
        material,
    };
    let (per_twig, extra) = (count / twigs.len(), count % twigs.len());
    for (t, twig) in twigs.iter().enumerate() {
        let leaves = per_twig + usize::from(t < extra);
        for _ in 0..leaves {
            let s = rng.range(0.15, 1.2);
            let (point, axis, _) = twig.along(s);
            let point = point + axis * (s - 1.0).max(0.0) * 0.08;
            let offset = {
                let d = rng.direction();
                (d - axis * d.dot(axis)).normalize_or(perpendicular(axis))
            };
            let centre = point + offset * rng.range(0.006, 0.035);
            let normal = (Vec3::Y + rng.direction() * 0.7 + offset * 0.3).normalize();
            let along = (offset + axis * 0.5 + rng.direction() * 0.3).normalize();
            let u = (along - normal * along.dot(normal)).normalize_or(perpendicular(normal));
            let w = normal.cross(u);
            let (hu, hw) = (u * (0.5 * LEAF_SIZE.x), w * (0.5 * LEAF_SIZE.y));
            let base = mesh.positions.len() as u32;
            mesh.positions.extend([
                centre - hu - hw,
                centre + hu - hw,
                centre + hu + hw,
                centre - hu + hw,
            ]);
            mesh.normals.extend([normal; 4]);
            mesh.uvs.extend([
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 1.0),
            ]);
            mesh.indices.push([base, base + 1, base + 2]);
            mesh.indices.push([base + 2, base + 3, base]);
        }
    }
    mesh
}

/// The mobile ball: a UV sphere of [`BALL_RADIUS`] round the origin with smooth normals.
fn ball_mesh(material: u32) -> Mesh {
    let (slices, stacks) = (BALL_SLICES, BALL_STACKS);
    let mut mesh = Mesh {
        name: "ball".into(),
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        indices: Vec::new(),
        material,
    };
    let mut vertex = |n: Vec3, uv: Vec2| {
        mesh.positions.push(n * BALL_RADIUS);
        mesh.normals.push(n);
        mesh.uvs.push(uv);
    };
    vertex(Vec3::Y, Vec2::new(0.5, 1.0));
    for j in 1..stacks {
        let theta = PI * j as f32 / stacks as f32;
        for i in 0..slices {
            let phi = TAU * i as f32 / slices as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            vertex(
                n,
                Vec2::new(i as f32 / slices as f32, 1.0 - j as f32 / stacks as f32),
            );
        }
    }
    vertex(-Vec3::Y, Vec2::new(0.5, 0.0));
    let bottom = mesh.positions.len() as u32 - 1;
    let ring = |j: u32, i: u32| 1 + (j - 1) * slices + i % slices;
    for i in 0..slices {
        mesh.indices.push([0, ring(1, i), ring(1, i + 1)]);
    }
    for j in 1..stacks - 1 {
        for i in 0..slices {
            let (a0, a1, b0, b1) = (
                ring(j, i),
                ring(j, i + 1),
                ring(j + 1, i),
                ring(j + 1, i + 1),
            );
            mesh.indices.push([a0, b0, b1]);
            mesh.indices.push([a0, b1, a1]);
        }
    }
    for i in 0..slices {
        mesh.indices
            .push([ring(stacks - 1, i), bottom, ring(stacks - 1, i + 1)]);
    }
    mesh
}

/// The square light, facing down.
fn light_mesh(material: u32) -> Mesh {
    let h = 0.5 * LIGHT_SIZE;
    let c = LIGHT_CENTRE;
    Mesh {
        name: "light".into(),
        positions: vec![
            c + Vec3::new(-h, 0.0, -h),
            c + Vec3::new(h, 0.0, -h),
            c + Vec3::new(h, 0.0, h),
            c + Vec3::new(-h, 0.0, h),
        ],
        normals: vec![-Vec3::Y; 4],
        uvs: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ],
        indices: vec![[0, 1, 2], [2, 3, 0]],
        material,
    }
}
