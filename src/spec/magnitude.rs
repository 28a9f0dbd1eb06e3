//! Magnitudes f64 arithmetic can carry through the closed forms: every number a point's spec gives
//! (a float anywhere in its tree: swept, `--set` or written in the file) must be 0 or lie within
//! 10⁻¹⁰⁰ … 10¹⁰⁰ in magnitude.
//!
//! Why these bounds: the theory columns raise parameters to small powers and multiply a few of them
//! (ρ·r³, 1/(Q²(1 − Q)), n_R·∛n_P·Q⁻²); with every factor within 10^±100 a product of three stays
//! within 10^±300, inside f64's range (about 10^±308, normal numbers from 2.2·10⁻³⁰⁸). A value
//! outside it passed each key's own range check but overflowed a theory column of its point only
//! after the points before it had run; now `raycost check` refuses it, naming the key and the point.
//! No shipped experiment comes within 10^±20 of the bounds (units from nm to km span 10^±12).

use crate::toml_text::de::KeyError;

/// The largest magnitude a point's number may have.
pub const LARGEST: f64 = 1e100;
/// The smallest non-zero magnitude a point's number may have.
pub const SMALLEST: f64 = 1e-100;

/// Refuses the first number of `tree` (a point's spec tree) outside the bounds, naming its dotted
/// key.
pub fn check_point(tree: &toml::Table) -> Result<(), KeyError> {
    walk("", tree)
}

fn walk(prefix: &str, t: &toml::Table) -> Result<(), KeyError> {
    for (k, v) in t {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        value(&key, v)?;
    }
    Ok(())
}

fn value(key: &str, v: &toml::Value) -> Result<(), KeyError> {
    match v {
        toml::Value::Float(x) if x.is_finite() && *x != 0.0 => {
            let m = x.abs();
            if !(SMALLEST..=LARGEST).contains(&m) {
                return Err(KeyError::new(
                    key,
                    format!(
                        "{x:e} is outside 1e-100 … 1e100 in magnitude: the closed forms of this \
                         point would overflow or underflow f64 (give 0 or a magnitude within \
                         1e-100 … 1e100; change the unit of the scene if its numbers are extreme)"
                    ),
                ));
            }
            Ok(())
        }
        toml::Value::Table(t) => walk(key, t),
        toml::Value::Array(a) => a.iter().try_for_each(|x| value(key, x)),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extreme_numbers_are_refused_by_key() {
        let t: toml::Table = "[detp]\nq = 1e-200\n".parse().expect("toml");
        let e = check_point(&t).expect_err("tiny");
        assert_eq!(e.key, "detp.q");
        assert!(e.message.contains("1e-200"), "{}", e.message);
        let t: toml::Table = "[scene]\nclass = [{radius = 1e150}]\n"
            .parse()
            .expect("toml");
        assert_eq!(check_point(&t).expect_err("huge").key, "scene.class.radius");
        let ok: toml::Table = "a = 0.0\nb = 1e-12\nc = -3e99\nd = 7\ne = \"x\"\n"
            .parse()
            .expect("toml");
        assert!(check_point(&ok).is_ok());
    }
}
