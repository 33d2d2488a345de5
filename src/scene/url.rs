//! A whole scene in a link: its TOML compressed (zlib) and written in URL-safe base64, the value
//! of the browser page's `toml` parameter (`index.html?toml=…`, `src/web/`). Both sizes are
//! bounded: the parameter before anything is decoded, the text while it is inflated, so that a
//! link cannot make the page allocate without bound.

/// The longest `toml` parameter accepted, in characters (a scene of the bundled kind takes
/// under 2 000).
pub const MAX_PARAM_CHARS: usize = 32 * 1024;

/// The longest scene text a link may inflate to, in bytes.
pub const MAX_TEXT_BYTES: usize = 1024 * 1024;

/// Why a link's scene cannot be read.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum UrlSceneError {
    #[error("the scene in the link is {chars} characters long; the limit is {MAX_PARAM_CHARS}")]
    TooLong { chars: usize },
    #[error("the scene in the link is not URL-safe base64: {0}")]
    Base64(String),
    #[error("the scene in the link does not inflate (not zlib data, or cut short)")]
    Inflate,
    #[error("the scene in the link inflates to more than {MAX_TEXT_BYTES} bytes")]
    TooLarge,
    #[error("the scene in the link is not UTF-8 text")]
    NotText,
}

/// The zlib stream of `bytes`, compressed as tightly as zlib goes.
fn compress(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut encoder = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    encoder.write_all(bytes).and_then(|()| encoder.finish()).expect("compressing into memory cannot fail")
}

/// The `toml` parameter for `toml_text`.
pub fn encode(toml_text: &str) -> String {
    base64::encode_config(compress(toml_text.as_bytes()), base64::URL_SAFE_NO_PAD)
}

/// The scene text of a `toml` parameter.
pub fn decode(param: &str) -> Result<String, UrlSceneError> {
    let chars = param.chars().count();
    if chars > MAX_PARAM_CHARS {
        return Err(UrlSceneError::TooLong { chars });
    }
    let zlib = base64::decode_config(param.trim_end_matches('='), base64::URL_SAFE_NO_PAD)
        .map_err(|e| UrlSceneError::Base64(e.to_string()))?;
    // One byte past the limit tells a text at the limit from a longer one.
    let mut bytes = Vec::new();
    let inflater = flate2::read::ZlibDecoder::new(zlib.as_slice());
    std::io::Read::read_to_end(&mut std::io::Read::take(inflater, MAX_TEXT_BYTES as u64 + 1), &mut bytes)
        .map_err(|_| UrlSceneError::Inflate)?;
    if bytes.len() > MAX_TEXT_BYTES {
        return Err(UrlSceneError::TooLarge);
    }
    String::from_utf8(bytes).map_err(|_| UrlSceneError::NotText)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_survives_the_link() {
        let text = include_str!("../../scenes/plant2.toml");
        let param = encode(text);
        assert!(param.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_'), "{param}");
        assert!(param.len() < text.len(), "{} characters for {} bytes", param.len(), text.len());
        assert_eq!(decode(&param).as_deref(), Ok(text));
    }

    #[test]
    fn bad_links_are_refused_with_the_reason() {
        let long = "A".repeat(MAX_PARAM_CHARS + 1);
        assert_eq!(decode(&long), Err(UrlSceneError::TooLong { chars: MAX_PARAM_CHARS + 1 }));
        assert!(matches!(decode("a+b/"), Err(UrlSceneError::Base64(_))));
        assert_eq!(decode(&encode("x")[..4]), Err(UrlSceneError::Inflate));
        // Two megabytes of one letter compress to a few kilobytes: refused while inflating.
        let bomb = encode(&"x".repeat(2 * MAX_TEXT_BYTES));
        assert!(bomb.len() <= MAX_PARAM_CHARS, "{}", bomb.len());
        assert_eq!(decode(&bomb), Err(UrlSceneError::TooLarge));
        let not_text = base64::encode_config(compress(&[0xff, 0xfe]), base64::URL_SAFE_NO_PAD);
        assert_eq!(decode(&not_text), Err(UrlSceneError::NotText));
    }
}
