//! The three ways text reaches the page, each made safe once: [`text`] for element content and
//! attribute values, [`href`] for a relative path in `href`/`src`, and [`anchor`] for an `id`. Every
//! string from a result folder (file names, metadata, CSV cells, claims) goes through one of them,
//! so a `<` in a spec description or a `"` in a file name cannot break the page.

use std::path::{Component, Path, PathBuf};

/// `s` escaped for HTML element content and quoted attribute values (`&`, `<`, `>`, `"`, `'`).
pub fn text(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A relative path as a URL path for `href`/`src`: `/`-separated, every byte but the unreserved
/// ones (RFC 3986: letters, digits, `-._~`) percent-encoded, so spaces, `#`, `?`, `%`, quotes and
/// non-ASCII names all survive; the result needs no further escaping inside a quoted attribute.
pub fn href(rel: &Path) -> String {
    let mut out = String::new();
    for (i, c) in rel.components().enumerate() {
        if i > 0 {
            out.push('/');
        }
        let part = match c {
            Component::ParentDir => "..".to_string(),
            Component::CurDir => ".".to_string(),
            c => c.as_os_str().to_string_lossy().into_owned(),
        };
        for b in part.bytes() {
            if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
                out.push(b as char);
            } else {
                out.push_str(&format!("%{b:02X}"));
            }
        }
    }
    out
}

/// The inverse of [`href`] (for tests and the browser check): percent-decoding of a relative URL.
pub fn unhref(url: &str) -> PathBuf {
    let bytes = url.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 3 <= bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    PathBuf::from(String::from_utf8_lossy(&out).into_owned())
}

/// An `id` for a section: `prefix-` and the name with every character outside `[A-Za-z0-9_-]`
/// replaced by `_` (ids must be unique and need no escaping in `href="#…"`).
pub fn anchor(prefix: &str, name: &str) -> String {
    let body: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{prefix}-{body}")
}

/// The path of `to` relative to the folder `from` (both absolute and canonical): `../x/y.csv`.
pub fn relative(from: &Path, to: &Path) -> PathBuf {
    crate::output::location::relative(from, to)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_escapes_every_markup_character() {
        assert_eq!(
            text(r#"<script>alert("x&y's")</script>"#),
            "&lt;script&gt;alert(&quot;x&amp;y&#39;s&quot;)&lt;/script&gt;"
        );
        assert_eq!(text("ρ = 1 ± 0.1"), "ρ = 1 ± 0.1");
    }

    #[test]
    fn hrefs_encode_what_a_url_cannot_hold_and_decode_back() {
        let p = Path::new("../a b/x#1?\"ρ\".csv");
        let h = href(p);
        assert_eq!(h, "../a%20b/x%231%3F%22%CF%81%22.csv");
        assert_eq!(unhref(&h), p);
        assert_eq!(unhref("%2"), Path::new("%2"));
    }

    #[test]
    fn relative_paths_climb_to_the_common_folder() {
        assert_eq!(
            relative(
                Path::new("/r/results/report"),
                Path::new("/r/results/a/a.csv")
            ),
            Path::new("../a/a.csv")
        );
        assert_eq!(
            relative(Path::new("/r/out"), Path::new("/r/out/img/x.png")),
            Path::new("img/x.png")
        );
    }

    #[test]
    fn anchors_hold_only_safe_characters() {
        assert_eq!(anchor("exp", "a b\"<c>"), "exp-a_b__c_");
    }
}
