//! Radiosity to 8-bit palette indices: one exposure for all frames of a picture (the 99th
//! percentile of the lit pixels' radiosity maps to 0.9), clamped, gamma 1/2.2.

/// A pixel's radiosity B = albedo·E/π; NaN: sees nothing; +∞: sees an emitter.
pub type Radiosity = f64;

/// Grey levels, or a false-colour ramp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Palette {
    /// Index i is grey level i (0 black: nothing seen; 255 white: emitters and the brightest).
    Grey,
    /// Index 0 black (nothing seen), 255 white (emitters), 1…254 a viridis-like ramp.
    Colour,
}

impl Palette {
    /// 256 RGB triples.
    pub fn rgb(self) -> Vec<u8> {
        let mut p = Vec::with_capacity(768);
        for i in 0..=255u8 {
            let c = match self {
                Palette::Grey => [i, i, i],
                Palette::Colour => match i {
                    0 => [0, 0, 0],
                    255 => [255, 255, 255],
                    _ => ramp(f64::from(i - 1) / 253.0),
                },
            };
            p.extend_from_slice(&c);
        }
        p
    }

    /// The index of tone value v ∈ [0, 1] (after gamma).
    fn index(self, v: f64) -> u8 {
        let v = v.clamp(0.0, 1.0);
        match self {
            Palette::Grey => (v * 255.0).round() as u8,
            Palette::Colour => 1 + (v * 253.0).round() as u8,
        }
    }
}

/// Viridis, five stops, linear in between.
fn ramp(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let x = t.clamp(0.0, 1.0) * 4.0;
    let k = (x.floor() as usize).min(3);
    let f = x - k as f64;
    let mut c = [0u8; 3];
    for (ch, out) in c.iter_mut().enumerate() {
        *out = (STOPS[k][ch] * (1.0 - f) + STOPS[k + 1][ch] * f).round() as u8;
    }
    c
}

/// The exposure: 0.9 over the 99th percentile of the finite radiosities (1 when there are none or
/// it is 0).
pub fn exposure<'a>(images: impl IntoIterator<Item = &'a [Radiosity]>) -> f64 {
    let mut v: Vec<f64> = images
        .into_iter()
        .flat_map(|im| im.iter().copied())
        .filter(|b| b.is_finite())
        .collect();
    if v.is_empty() {
        return 1.0;
    }
    let k = ((v.len() as f64 * 0.99) as usize).min(v.len() - 1);
    let (_, p99, _) = v.select_nth_unstable_by(k, f64::total_cmp);
    if *p99 > 0.0 {
        0.9 / *p99
    } else {
        1.0
    }
}

/// Palette indices of one image.
pub fn indices(b: &[Radiosity], exposure: f64, palette: Palette) -> Vec<u8> {
    b.iter()
        .map(|&x| {
            if x.is_nan() {
                0
            } else if x == f64::INFINITY {
                255
            } else {
                palette.index((x * exposure).clamp(0.0, 1.0).powf(1.0 / 2.2))
            }
        })
        .collect()
}

/// Side by side: images of `w × h` indices, left to right, as one `(w·k) × h` image.
pub fn strip(images: &[Vec<u8>], w: usize, h: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(images.len() * w * h);
    for row in 0..h {
        for im in images {
            out.extend_from_slice(&im[row * w..(row + 1) * w]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_99th_percentile_maps_to_0_9_and_specials_are_black_and_white() {
        let b: Vec<f64> = (0..1000).map(f64::from).collect();
        let e = exposure([b.as_slice()]);
        assert!((e * 990.0 - 0.9).abs() < 1e-12);
        let ix = indices(
            &[f64::NAN, f64::INFINITY, 0.0, 990.0, 1e9],
            e,
            Palette::Grey,
        );
        let g = (0.9f64.powf(1.0 / 2.2) * 255.0).round() as u8;
        assert_eq!(ix, vec![0, 255, 0, g, 255]);
        let c = indices(&[f64::NAN, f64::INFINITY, 0.0], e, Palette::Colour);
        assert_eq!(c, vec![0, 255, 1]);
        assert_eq!(Palette::Colour.rgb().len(), 768);
    }

    #[test]
    fn strips_interleave_rows() {
        let a = vec![1, 2, 3, 4];
        let b = vec![5, 6, 7, 8];
        assert_eq!(strip(&[a, b], 2, 2), vec![1, 2, 5, 6, 3, 4, 7, 8]);
    }
}
