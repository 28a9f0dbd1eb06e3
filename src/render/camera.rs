//! Primary rays of a pinhole camera (vertical field of view) and the points they see.

use glam::DVec3;
use rayon::prelude::*;

use crate::detp::disc::Discs;
use crate::lt::{Camera, Scene};

/// The camera's frame: forward, right and up unit vectors and tan(fov/2).
#[derive(Clone, Copy, Debug)]
pub struct Pinhole {
    /// Eye.
    pub eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tan_half: f64,
    width: f64,
    height: f64,
}

impl Pinhole {
    /// The pinhole of `cam` for an image of `width × height` pixels. Right = forward × up, so a
    /// right-handed scene with y up, seen along +z, has −x on the image's right.
    pub fn new(cam: &Camera, width: u32, height: u32) -> Self {
        let forward = (cam.look_at - cam.eye).normalize();
        let right = forward.cross(cam.up).normalize();
        let up = right.cross(forward);
        Self {
            eye: cam.eye,
            forward,
            right,
            up,
            tan_half: (0.5 * cam.fov_deg).to_radians().tan(),
            width: f64::from(width),
            height: f64::from(height),
        }
    }

    /// The unit direction through image position (x, y), in pixels from the top-left corner (pixel
    /// (i, j)'s centre is (i + ½, j + ½)).
    pub fn dir(&self, x: f64, y: f64) -> DVec3 {
        let aspect = self.width / self.height;
        let sx = (2.0 * x / self.width - 1.0) * self.tan_half * aspect;
        let sy = (1.0 - 2.0 * y / self.height) * self.tan_half;
        (self.forward + sx * self.right + sy * self.up).normalize()
    }
}

/// What one pixel sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pixel {
    /// Nothing: black.
    Miss,
    /// An emitting surface: white.
    Emitter,
    /// A lit surface: the pixel's sample disc and the surface's albedo.
    Disc {
        /// Index into the view's discs.
        disc: u32,
        /// Albedo of the surface seen.
        albedo: f64,
    },
}

/// The pixels of one frame and the sample discs at their visible points.
#[derive(Clone, Debug)]
pub struct View {
    /// Pixels.
    pub width: u32,
    /// Pixels.
    pub height: u32,
    /// Row-major, top row first.
    pub pixels: Vec<Pixel>,
    /// One disc per lit pixel: at the first hit of the pixel's centre ray, with the surface normal
    /// turned to face the camera.
    pub discs: Discs,
}

/// Shoots one ray through every pixel centre of `scene` (posed at the frame wanted) and puts a
/// disc of radius `d` at each visible point.
pub fn view(scene: &Scene, cam: &Camera, width: u32, height: u32, d: f64) -> View {
    let pin = Pinhole::new(cam, width, height);
    let t_min = scene.precision().offset();
    let hits: Vec<Option<(DVec3, DVec3, u32)>> = (0..width as usize * height as usize)
        .into_par_iter()
        .map(|k| {
            let (i, j) = (k % width as usize, k / width as usize);
            let dir = pin.dir(i as f64 + 0.5, j as f64 + 0.5);
            let (hit, _) = scene.first_two_hits(pin.eye, dir, t_min, None);
            hit.map(|h| {
                let p = pin.eye + dir * h.t;
                let mut n = scene.normal(h.prim, p);
                if n.dot(dir) > 0.0 {
                    n = -n;
                }
                (p, n, h.surface)
            })
        })
        .collect();
    let (mut centers, mut normals) = (Vec::new(), Vec::new());
    let pixels = hits
        .into_iter()
        .map(|h| match h {
            None => Pixel::Miss,
            Some((p, n, s)) => {
                let surf = &scene.surfaces[s as usize];
                if surf.emission > 0.0 {
                    Pixel::Emitter
                } else if p.is_finite() && n.is_finite() && n.length() > 0.0 {
                    centers.push(p);
                    normals.push(n);
                    Pixel::Disc {
                        disc: centers.len() as u32 - 1,
                        albedo: surf.albedo,
                    }
                } else {
                    Pixel::Miss
                }
            }
        })
        .collect();
    View {
        width,
        height,
        pixels,
        discs: Discs::new(centers, normals, d).expect("finite visible points and d > 0"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(w: u32, h: u32) -> Camera {
        Camera {
            eye: DVec3::new(1.0, 2.0, -5.0),
            look_at: DVec3::new(0.5, 1.0, 3.0),
            up: DVec3::Y,
            fov_deg: 40.0,
            width: w,
            height: h,
        }
    }

    #[test]
    fn the_image_centre_looks_at_look_at() {
        for (w, h) in [(256, 256), (400, 300), (7, 3)] {
            let c = cam(w, h);
            let pin = Pinhole::new(&c, w, h);
            let d = pin.dir(f64::from(w) / 2.0, f64::from(h) / 2.0);
            let want = (c.look_at - c.eye).normalize();
            assert!((d - want).length() < 1e-12, "{d} vs {want}");
        }
    }

    #[test]
    fn the_vertical_fov_spans_the_image_height_and_right_is_forward_cross_up() {
        let c = Camera {
            eye: DVec3::ZERO,
            look_at: DVec3::Z,
            up: DVec3::Y,
            fov_deg: 60.0,
            width: 200,
            height: 100,
        };
        let pin = Pinhole::new(&c, 200, 100);
        let top = pin.dir(100.0, 0.0);
        let angle = top.angle_between(DVec3::Z).to_degrees();
        assert!((angle - 30.0).abs() < 1e-9, "{angle}");
        assert!(top.y > 0.0);
        // +z forward, y up: the image's right is −x.
        assert!(pin.dir(200.0, 50.0).x < 0.0);
    }
}
