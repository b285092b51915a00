//! Whether light from outside the scene can reach what a camera sees: random walks from the
//! camera's position through the scene's surfaces, on the CPU BVH, counting those that leave
//! it. The default light (default_light.rs) is not given to a camera inside a closed room: a sky
//! there lights nothing, yet every renderer would spend light samples on it, drawn by power.
//!
//! Each walk starts in a uniformly random direction (all around, not only in the view: a
//! window behind the camera still lights the room) and bounces off up to [`BOUNCES`] opaque
//! surfaces in a cosine-distributed direction on the side it arrived from. Surfaces light can
//! pass (glass, blended or alpha-tested materials) are crossed as if open, so a window counts
//! as one. A walk that hits nothing has left the scene. A camera outside the scene's bounds
//! sees out at once and is not traced.

use crate::accel::bvh::rays::SplitMix64;
use crate::accel::bvh::{Hit, SceneBvh, closest_hit};
use crate::scene::{AlphaMode, Pose, Scene};
use glam::Vec3;

/// Walks traced from the camera.
pub const PATHS: usize = 4096;
/// Surfaces a walk bounces off before it is given up as enclosed: the sky lights what the
/// camera sees through a window around a corner after two.
pub const BOUNCES: usize = 4;

/// What the walks found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reach {
    /// The camera is outside the scene's bounds.
    Outside,
    /// `escaped` of `paths` walks left the scene.
    Walks { escaped: usize, paths: usize },
}

impl Reach {
    /// Whether any light from outside reaches the camera's surroundings.
    pub fn open(self) -> bool {
        match self {
            Reach::Outside => true,
            Reach::Walks { escaped, .. } => escaped > 0,
        }
    }
}

/// Traces [`PATHS`] walks of at most [`BOUNCES`] bounces from `from` through `scene` at `pose`.
pub fn from_camera(scene: &Scene, pose: &Pose, from: Vec3) -> Reach {
    let (lo, hi) = scene.bounds(pose);
    if !(from.cmpgt(lo) & from.cmplt(hi)).all() {
        return Reach::Outside;
    }
    let bvh = SceneBvh::build(scene, pose);
    // Offsets off a surface, relative to the scene's size (as the shaders' ray origins).
    let eps = 1e-4 * (hi - lo).max_element().max(1e-3);
    let mut rng = SplitMix64::new(0x5ca1_ab1e);
    let escaped = (0..PATHS).filter(|_| walk_escapes(scene, pose, &bvh, from, eps, &mut rng)).count();
    Reach::Walks { escaped, paths: PATHS }
}

/// One walk: true when it leaves the scene within [`BOUNCES`] opaque bounces.
fn walk_escapes(scene: &Scene, pose: &Pose, bvh: &SceneBvh, from: Vec3, eps: f32, rng: &mut SplitMix64) -> bool {
    let (mut origin, mut dir) = (from, uniform_sphere(rng.unit(), rng.unit()));
    let mut bounces = 0;
    // Crossings of open surfaces count too, so a stack of glass panes cannot loop forever.
    for _ in 0..4 * BOUNCES {
        // Alpha-tested candidates never count: a cut-out is crossed as if open.
        let Some(hit) = closest_hit(bvh, origin, dir, 0.0, f32::INFINITY, 0xFF, |_, _, _, _| false) else {
            return true;
        };
        let Surface { position: p, facing, see_through } = Surface::at(scene, pose, &hit, origin, dir);
        if see_through {
            origin = p - facing * eps;
            continue;
        }
        bounces += 1;
        if bounces > BOUNCES || facing == Vec3::ZERO {
            return false;
        }
        origin = p + facing * eps;
        dir = cosine_around(facing, rng.unit(), rng.unit());
    }
    false
}

/// Where a CPU ray hit: the point, the triangle's normal on the side the ray arrived from, and
/// whether light passes the surface (glass, blended or alpha-tested materials), which the walks
/// and render::light_view's rays cross as if open.
pub(crate) struct Surface {
    pub position: Vec3,
    pub facing: Vec3,
    pub see_through: bool,
}

impl Surface {
    pub fn at(scene: &Scene, pose: &Pose, hit: &Hit, origin: Vec3, dir: Vec3) -> Self {
        let instance = &scene.instances[hit.instance as usize];
        let mesh = &scene.meshes[instance.mesh as usize];
        let world = pose.world[instance.node as usize];
        let corner = |k: usize| {
            let index = mesh.indices[hit.primitive as usize * 3 + k] as usize;
            world.transform_point3(Vec3::from(mesh.vertices[index].position))
        };
        let normal = (corner(1) - corner(0)).cross(corner(2) - corner(0)).normalize_or_zero();
        let material = scene.materials.get(mesh.material as usize);
        Self {
            position: origin + dir * hit.t,
            facing: if normal.dot(dir) > 0.0 { -normal } else { normal },
            see_through: material.is_some_and(|m| m.is_transmissive() || m.alpha_mode != AlphaMode::Opaque),
        }
    }
}

/// A uniformly distributed unit vector.
fn uniform_sphere(u: f32, v: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A cosine-distributed unit vector in the hemisphere around `n`.
fn cosine_around(n: Vec3, u: f32, v: f32) -> Vec3 {
    let (t, b) = n.any_orthonormal_pair();
    let r = u.sqrt();
    let phi = std::f32::consts::TAU * v;
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u).max(0.0).sqrt()).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Instance, Material, builtin};

    /// A 2 x 2 x 2 room of six walls around the origin; `open` leaves the +X wall out and
    /// `glass` makes it transmissive.
    fn room(open: bool, glass: bool) -> Scene {
        let mut s = Scene::default();
        s.materials.push(Material { name: "wall".into(), ..Default::default() });
        s.materials.push(Material { name: "glass".into(), transmission: 1.0, ..Default::default() });
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                if open && axis == 0 && sign > 0.0 {
                    continue;
                }
                let (mut c, mut u, mut v) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
                c[axis] = sign;
                u[(axis + 1) % 3] = 2.0;
                v[(axis + 2) % 3] = 2.0;
                let material = u32::from(glass && axis == 0 && sign > 0.0);
                s.meshes.push(builtin::quad(c, u, v, material));
                s.instances.push(Instance { mesh: s.meshes.len() as u32 - 1, node: 0 });
            }
        }
        s.nodes.push(builtin::node("n", Vec3::ZERO));
        s
    }

    fn reach(scene: &Scene, from: Vec3) -> Reach {
        from_camera(scene, &scene.evaluate(0.0), from)
    }

    #[test]
    fn no_walk_leaves_a_closed_room() {
        assert_eq!(reach(&room(false, false), Vec3::new(-0.3, 0.2, 0.1)), Reach::Walks { escaped: 0, paths: PATHS });
    }

    #[test]
    fn walks_leave_through_an_open_wall_or_a_window() {
        for (what, scene) in [("open", room(true, false)), ("glass", room(false, true))] {
            let Reach::Walks { escaped, paths } = reach(&scene, Vec3::new(-0.5, 0.0, 0.0)) else { panic!("{what}") };
            // The open wall alone subtends about 0.1 of the sphere from there; bounces add more.
            let share = escaped as f32 / paths as f32;
            assert!(share > 0.1 && share < 0.9, "{what}: {escaped} of {paths} walks left");
            assert!(Reach::Walks { escaped, paths }.open());
        }
    }

    #[test]
    fn a_camera_outside_the_bounds_sees_out() {
        assert_eq!(reach(&room(false, false), Vec3::new(0.0, 0.0, 5.0)), Reach::Outside);
        assert!(Reach::Outside.open());
    }
}
