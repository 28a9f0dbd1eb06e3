//! The AFF parser: each directive of a file (and of the files it includes) read with the lexer's
//! typed reads and handed to the scene builder. [`Loader::directive`] only dispatches; each
//! directive has its own function.

use std::path::Path;
use std::rc::Rc;

use glam::{DAffine3, DVec3};

use super::build::{
    mean, trs, Frame, Link, Loader, PartBuild, PatchBuild, MAX_COUNT, MAX_INCLUSIONS,
    MAX_SCENE_BYTES,
};
use super::lexer::{Ctx, Lexer, Tok};
use crate::error::InputError;
use crate::lt::spline::{axis_angle_deg, KbKey, KbTrack, KbTransform};
use crate::lt::{Camera, Light};

/// Includes nested deeper than this are taken for a cycle.
pub(super) const MAX_INCLUDE_DEPTH: usize = 64;

impl Loader {
    pub(super) fn file(
        &mut self,
        path: &Path,
        bytes: Rc<[u8]>,
        depth: usize,
    ) -> Result<(), InputError> {
        let mut cx = Ctx {
            name: path.display().to_string(),
            lx: Lexer::new(&bytes),
            key: "",
            at: (1, 1),
        };
        self.bytes_read += bytes.len() as u64;
        if self.bytes_read > MAX_SCENE_BYTES {
            return Err(cx.err_at(
                (1, 1),
                format!(
                    "the scene expands to more than {} MiB of text, includes counted each time they \
                     are included ({} inclusions so far): an include fan-out? (at most {} MiB)",
                    MAX_SCENE_BYTES >> 20,
                    self.inclusions,
                    MAX_SCENE_BYTES >> 20
                ),
            ));
        }
        let base = self.stack.len();
        let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
        while let Some(t) = cx.lx.next() {
            cx.at = (t.line, t.col);
            self.directive(&mut cx, t, &dir, depth, base)?;
        }
        if self.stack.len() > base {
            let f = self.top();
            cx.key = f.key;
            return Err(cx.err_at(
                f.open,
                format!(
                    "unterminated block: this `{{` (of `{}`) has no matching `}}` before the end of the file",
                    f.key
                ),
            ));
        }
        Ok(())
    }

    pub(super) fn open_block(
        &mut self,
        cx: &mut Ctx,
        frame: impl FnOnce(&mut Self) -> Frame,
    ) -> Result<(), InputError> {
        let t = cx.tok("`{`")?;
        if !t.is("{") {
            return Err(cx.err_at(
                (t.line, t.col),
                format!(
                    "expected `{{` to open the `{}` block, found `{}`",
                    cx.key,
                    t.show()
                ),
            ));
        }
        let mut f = frame(self);
        f.open = (t.line, t.col);
        f.key = cx.key;
        self.stack.push(f);
        Ok(())
    }

    pub(super) fn directive(
        &mut self,
        cx: &mut Ctx,
        t: Tok,
        dir: &Path,
        depth: usize,
        base: usize,
    ) -> Result<(), InputError> {
        const KEYS: [&str; 20] = [
            "b", "v", "am", "l", "f", "fm", "p", "pp", "s", "c", "m", "tt", "ttp", "tpa", "x",
            "xs", "k", "a", "i", "}",
        ];
        let Some(key) = KEYS.iter().copied().find(|k| t.is(k)) else {
            cx.key = "";
            let what = if t.number().is_some() {
                format!(
                    "unexpected number `{}` where a directive was expected (too many numbers for the previous directive?)",
                    t.show()
                )
            } else if t.is("{") {
                "a `{` must follow `xs …` or `x NAME`".to_string()
            } else {
                format!(
                    "unknown directive `{}`: expected one of b v am l f fm p pp s c m tt ttp tpa x xs k a i, `}}`, or a % / # comment",
                    t.show()
                )
            };
            let mut e = cx.err_at((t.line, t.col), what);
            e.key = Some(t.show());
            return Err(e);
        };
        cx.key = key;
        match key {
            "b" | "am" => {
                cx.vec3("an RGB colour (3 numbers)")?;
            }
            "v" => self.viewpoint(cx)?,
            "l" => self.light(cx)?,
            "f" => self.material_nff(cx)?,
            "fm" => self.material_aff(cx)?,
            "p" | "pp" => self.polygon(cx, key)?,
            "s" => self.sphere_directive(cx)?,
            "c" => self.cone_directive(cx)?,
            "m" => self.mesh(cx)?,
            "tt" | "ttp" => self.textured(cx, key)?,
            "tpa" => self.animated_triangle(cx)?,
            "xs" => self.static_transform(cx)?,
            "x" => self.animated_transform(cx)?,
            "}" => self.close(cx, base)?,
            "k" => self.keyframes(cx)?,
            "a" => self.animation(cx)?,
            "i" => self.include(cx, dir, depth)?,
            _ => unreachable!("every key of KEYS is handled"),
        }
        Ok(())
    }

    /// `l X Y Z [R G B]`: a point light of the colour's mean power.
    fn light(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let p = cx.vec3("the light position X Y Z")?;
        let power = if cx.lx.peek().and_then(|t| t.number()).is_some() {
            mean(cx.vec3("the light colour R G B")?)
        } else {
            1.0
        };
        let f = self.top();
        if f.part.is_some() {
            self.counts.lights_in_movers += 1;
        }
        self.out.lights.push(Light::Point {
            position: f.local.transform_point3(p),
            power,
        });

        Ok(())
    }

    /// `f R G B Kd Ks Shine T ior`: an NFF material of albedo mean(RGB)·Kd.
    fn material_nff(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let rgb = cx.vec3("f R G B Kd Ks Shine T ior")?;
        let kd = cx.num("f R G B Kd Ks Shine T ior")?;
        for _ in 0..4 {
            cx.num("f R G B Kd Ks Shine T ior")?;
        }
        self.add_material(mean(rgb) * kd, &cx.name.clone(), cx.at);

        Ok(())
    }

    /// `fm`: an AFF material of albedo mean(diffuse).
    fn material_aff(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let what = "fm: ambient RGB, diffuse RGB, specular RGB, Shine T ior (12 numbers)";
        cx.vec3(what)?;
        let diffuse = cx.vec3(what)?;
        for _ in 0..6 {
            cx.num(what)?;
        }
        self.add_material(mean(diffuse), &cx.name.clone(), cx.at);

        Ok(())
    }

    /// `p N` / `pp N`: a polygon (with normals) fanned into triangles.
    fn polygon(&mut self, cx: &mut Ctx, key: &str) -> Result<(), InputError> {
        let n = cx.int("the number of polygon vertices", MAX_COUNT)?;
        if n < 3 {
            return Err(cx.err_at(
                cx.at,
                format!("a polygon needs at least 3 vertices, got {n}"),
            ));
        }
        let mut pts = Vec::with_capacity(n.min(1 << 16));
        for _ in 0..n {
            pts.push(cx.vec3("a polygon vertex X Y Z")?);
            if key == "pp" {
                cx.vec3("a vertex normal NX NY NZ")?;
            }
        }
        for i in 1..n - 1 {
            self.emit([pts[0], pts[i], pts[i + 1]]);
        }

        Ok(())
    }

    /// `s X Y Z R`: a sphere, tessellated.
    fn sphere_directive(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let c = cx.vec3("the sphere centre X Y Z")?;
        let r = cx.num("the sphere radius")?;
        self.counts.spheres += 1;
        self.sphere(c, r);

        Ok(())
    }

    /// `c` base radius apex radius: a cone or cylinder, tessellated.
    fn cone_directive(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let what = "c: base X Y Z radius, apex X Y Z radius (8 numbers)";
        let b = cx.vec3(what)?;
        let r0 = cx.num(what)?;
        let a = cx.vec3(what)?;
        let r1 = cx.num(what)?;
        self.counts.cones += 1;
        self.cone(b, r0, a, r1);

        Ok(())
    }

    /// `tt` / `ttp`: a textured triangle (texture ignored, counted).
    fn textured(&mut self, cx: &mut Ctx, key: &str) -> Result<(), InputError> {
        cx.tok("a texture name")?;
        let mut v = [DVec3::ZERO; 3];
        for p in &mut v {
            *p = cx.vec3("a vertex X Y Z")?;
            if key == "ttp" {
                cx.vec3("a vertex normal")?;
            }
            cx.num("texture coordinates U V")?;
            cx.num("texture coordinates U V")?;
        }
        self.counts.textured += 1;
        self.emit(v);

        Ok(())
    }

    /// `tpa N`: a triangle whose vertices are keyframed.
    fn animated_triangle(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let n = cx.int("the number of key times", MAX_COUNT)?;
        if n == 0 {
            return Err(cx.err_at(cx.at, "an animated triangle needs at least one key".into()));
        }
        let mut times = Vec::with_capacity(n.min(1 << 16));
        let mut vertices = Vec::with_capacity(n.min(1 << 16));
        let local = self.top().local;
        for _ in 0..n {
            let tm = cx.num("a key time")?;
            if times.last().is_some_and(|&l| tm < l) {
                return Err(cx.err_at(
                    cx.at,
                    format!("key time {tm} is before the previous one: times must not decrease"),
                ));
            }
            times.push(tm);
            let mut v = [DVec3::ZERO; 3];
            for p in &mut v {
                *p = local.transform_point3(cx.vec3("a vertex X Y Z")?);
                cx.vec3("a vertex normal NX NY NZ")?;
            }
            vertices.push(v);
        }
        let surface = self.surface();
        self.patches.push(PatchBuild {
            surface,
            times,
            vertices,
            part: self.top().part,
        });

        Ok(())
    }

    /// `xs S axis angle T {`: a static transform block.
    fn static_transform(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let what = "xs: scale SX SY SZ, rotation axis X Y Z and angle in degrees, translation TX TY TZ (10 numbers)";
        let s = cx.vec3(what)?;
        let axis = cx.vec3(what)?;
        let deg = cx.num(what)?;
        let tr = cx.vec3(what)?;
        let m = trs(s, axis, deg, tr);
        self.open_block(cx, |ld| {
            let f = ld.top();
            Frame {
                local: f.local * m,
                ..f
            }
        })?;

        Ok(())
    }

    /// `x NAME {`: an animated transform block (a mover part).
    fn animated_transform(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let name = cx.tok("the name of the animated transform")?.show();
        self.open_block(cx, |ld| {
            let f = ld.top();
            let (mover, mut chain) = match f.part {
                Some(p) => (ld.parts[p].mover, ld.parts[p].chain.clone()),
                None => {
                    ld.mover_names.push(name.clone());
                    (ld.mover_names.len() - 1, Vec::new())
                }
            };
            if f.local != DAffine3::IDENTITY {
                chain.push(Link::Fixed(f.local));
            }
            chain.push(Link::Anim(name));
            ld.parts.push(PartBuild {
                mover,
                chain,
                tris: Vec::new(),
            });
            Frame {
                local: DAffine3::IDENTITY,
                part: Some(ld.parts.len() - 1),
                open: (0, 0),
                key: "",
            }
        })?;

        Ok(())
    }

    /// `}`: closes the innermost block opened in this file.
    fn close(&mut self, cx: &mut Ctx, base: usize) -> Result<(), InputError> {
        if self.stack.len() <= base {
            return Err(cx.err_at(cx.at, "`}` without a matching `{` in this file".into()));
        }
        self.stack.pop();

        Ok(())
    }

    /// `a START END FRAMES`: the animation's time span.
    fn animation(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let s = cx.num("a START END FRAMES")?;
        let e = cx.num("a START END FRAMES")?;
        let n = cx.int("the number of frames", u32::MAX as usize)?;
        self.out.time = Some((s, e, n as u32));

        Ok(())
    }

    /// `i DETAIL FILE`: reads another file (relative to this one, or the root).
    fn include(&mut self, cx: &mut Ctx, dir: &Path, depth: usize) -> Result<(), InputError> {
        cx.num("the detail level of the include")?;
        let f = cx.tok("the file to include")?;
        let fname = f.show();
        let candidates = [dir.join(&fname), self.root.join(&fname)];
        // The first that exists; a folder, FIFO or device there is refused by what it is.
        if let Some(p) = candidates.iter().find(|p| p.exists()) {
            if let Err(why) = crate::error::regular_input(p) {
                return Err(cx.err_at((f.line, f.col), format!("include `{}`: {why}", p.display())));
            }
        }
        let Some(p) = candidates.iter().find(|p| p.is_file()) else {
            return Err(cx.err_at(
                (f.line, f.col),
                format!(
                    "include file `{fname}` not found (looked for {} and {})",
                    candidates[0].display(),
                    candidates[1].display()
                ),
            ));
        };
        self.inclusions += 1;
        if self.inclusions > MAX_INCLUSIONS {
            return Err(cx.err_at(
                (f.line, f.col),
                format!(
                    "more than {MAX_INCLUSIONS} inclusions, repeats counted: an include fan-out? \
                     (`{fname}` and the files it includes are included over and over)"
                ),
            ));
        }
        if depth + 1 > MAX_INCLUDE_DEPTH {
            return Err(cx.err_at(
                (f.line, f.col),
                format!("includes nested more than {MAX_INCLUDE_DEPTH} deep (an include cycle?)"),
            ));
        }
        let p = p.clone();
        let bytes = match self.cache.get(&p) {
            Some(b) => b.clone(),
            None => {
                let b: Rc<[u8]> = Rc::from(std::fs::read(&p).map_err(|e| {
                    cx.err_at(
                        (f.line, f.col),
                        format!("cannot read include `{}`: {e}", p.display()),
                    )
                })?);
                self.cache.insert(p.clone(), b.clone());
                b
            }
        };
        self.file(&p, bytes, depth + 1)?;

        Ok(())
    }

    pub(super) fn viewpoint(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let (mut from, mut at, mut up, mut angle, mut res) = (None, None, None, None, None);
        const WORDS: [&str; 6] = ["from", "at", "up", "angle", "hither", "resolution"];
        while let Some(t) = cx.lx.peek() {
            let Some(w) = WORDS.iter().copied().find(|w| t.is(w)) else {
                break;
            };
            cx.lx.next();
            match w {
                "from" => from = Some(cx.vec3("v: from X Y Z")?),
                "at" => at = Some(cx.vec3("v: at X Y Z")?),
                "up" => up = Some(cx.vec3("v: up X Y Z")?),
                "angle" => angle = Some(cx.num("v: angle (degrees)")?),
                "hither" => {
                    cx.num("v: hither distance")?;
                }
                _ => {
                    let w = cx.int("v: resolution width", u32::MAX as usize)?;
                    let h = cx.int("v: resolution height", u32::MAX as usize)?;
                    res = Some((w as u32, h as u32));
                }
            }
        }
        let missing: Vec<&str> = [
            ("from", from.is_none()),
            ("at", at.is_none()),
            ("up", up.is_none()),
            ("angle", angle.is_none()),
            ("resolution", res.is_none()),
        ]
        .iter()
        .filter(|x| x.1)
        .map(|x| x.0)
        .collect();
        let (Some(eye), Some(look_at), Some(up), Some(fov_deg), Some((width, height))) =
            (from, at, up, angle, res)
        else {
            return Err(cx.err_at(
                cx.at,
                format!(
                    "the viewpoint lacks {}: expected `v` followed by from, at, up, angle, hither, resolution",
                    missing.join(", ")
                ),
            ));
        };
        let m = self.top().local;
        self.out.camera = Some(Camera {
            eye: m.transform_point3(eye),
            look_at: m.transform_point3(look_at),
            up: m.transform_vector3(up),
            fov_deg,
            width,
            height,
        });
        Ok(())
    }

    pub(super) fn mesh(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        cx.word("vertices")?;
        let nv = cx.int("the number of vertices", MAX_COUNT)?;
        let mut verts = Vec::with_capacity(nv.min(1 << 16));
        for _ in 0..nv {
            verts.push(cx.vec3("a mesh vertex X Y Z")?);
        }
        let mut next = cx.tok("`normals`, `texturecoords` or `triangles`")?;
        let mut nn = 0;
        let has_normals = next.is("normals");
        if has_normals {
            nn = cx.int("the number of normals", MAX_COUNT)?;
            for _ in 0..nn {
                cx.vec3("a mesh normal X Y Z")?;
            }
            next = cx.tok("`texturecoords` or `triangles`")?;
        }
        let mut nt = 0;
        let has_tex = next.is("texturecoords");
        if has_tex {
            nt = cx.int("the number of texture coordinates", MAX_COUNT)?;
            if cx.lx.peek().is_some_and(|t| t.number().is_none()) {
                cx.lx.next(); // texture file name
            }
            for _ in 0..nt * 2 {
                cx.num("texture coordinates U V")?;
            }
            self.counts.textured += 1;
            next = cx.tok("`triangles`")?;
        }
        if !next.is("triangles") {
            return Err(cx.err_at(
                (next.line, next.col),
                format!(
                    "expected `triangles` in the mesh, found `{}` (after `vertices`, optional `normals`, optional `texturecoords`)",
                    next.show()
                ),
            ));
        }
        let ntri = cx.int("the number of triangles", MAX_COUNT)?;
        for _ in 0..ntri {
            let a = cx.int("a vertex index", nv)?;
            let b = cx.int("a vertex index", nv)?;
            let c = cx.int("a vertex index", nv)?;
            if has_normals {
                for _ in 0..3 {
                    cx.int("a normal index", nn)?;
                }
            }
            if has_tex {
                for _ in 0..3 {
                    cx.int("a texture-coordinate index", nt)?;
                }
            }
            self.emit([verts[a], verts[b], verts[c]]);
        }
        Ok(())
    }

    pub(super) fn keyframes(&mut self, cx: &mut Ctx) -> Result<(), InputError> {
        let name = cx.tok("the name of the animation")?.show();
        let t = cx.tok("`{`")?;
        if !t.is("{") {
            return Err(cx.err_at(
                (t.line, t.col),
                format!("expected `{{` after `k {name}`, found `{}`", t.show()),
            ));
        }
        let open = (t.line, t.col);
        let mut kb = KbTransform::default();
        loop {
            let Some(t) = cx.lx.next() else {
                return Err(cx.err_at(
                    open,
                    format!("unterminated block: the `{{` of `k {name}` has no matching `}}`"),
                ));
            };
            if t.is("}") {
                break;
            }
            let kind = if t.is("transl") {
                0
            } else if t.is("rot") {
                1
            } else if t.is("scale") {
                2
            } else if t.is("visibility") {
                3
            } else {
                return Err(cx.err_at(
                    (t.line, t.col),
                    format!(
                        "unknown keyframe track `{}` in `k {name}`: expected transl, rot, scale, visibility or `}}`",
                        t.show()
                    ),
                ));
            };
            let at = (t.line, t.col);
            let n = cx.int("the number of keys", MAX_COUNT)?;
            if kind == 3 {
                for _ in 0..n {
                    cx.num("a visibility key: time")?;
                    cx.num("a visibility key: 0 or 1")?;
                }
                self.counts.visibility += 1;
                continue;
            }
            let what = match kind {
                0 => "a translation key: time X Y Z tension continuity bias",
                1 => "a rotation key: time AX AY AZ angle° tension continuity bias",
                _ => "a scale key: time SX SY SZ tension continuity bias",
            };
            let mut vk = Vec::new();
            let mut qk = Vec::new();
            for _ in 0..n {
                let time = cx.num(what)?;
                let v = cx.vec3(what)?;
                let angle = if kind == 1 { cx.num(what)? } else { 0.0 };
                let (tension, continuity, bias) = (cx.num(what)?, cx.num(what)?, cx.num(what)?);
                if kind == 1 {
                    qk.push(KbKey {
                        time,
                        value: axis_angle_deg(v, angle),
                        tension,
                        continuity,
                        bias,
                    });
                } else {
                    vk.push(KbKey {
                        time,
                        value: v,
                        tension,
                        continuity,
                        bias,
                    });
                }
            }
            let bad = |m: crate::error::Invalid| cx.err_at(at, format!("in `k {name}`: {m}"));
            let ok = match kind {
                0 | 2 => vk.windows(2).all(|w| w[0].time <= w[1].time),
                _ => qk.windows(2).all(|w| w[0].time <= w[1].time),
            };
            if !ok {
                self.counts
                    .unsorted
                    .push(format!("{name} ({}:{})", cx.name, at.0));
            }
            match kind {
                0 => kb.translate = Some(KbTrack::new(vk).map_err(bad)?),
                1 => kb.rotate = Some(KbTrack::new(qk).map_err(bad)?),
                _ => kb.scale = Some(KbTrack::new(vk).map_err(bad)?),
            }
        }
        if name == "camera" {
            self.out.camera_animation = Some(kb);
        } else if self.anims.insert(name.clone(), kb).is_some() {
            self.counts.duplicate_keys.push(name);
        }
        Ok(())
    }
}
