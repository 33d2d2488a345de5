//! serde's and toml's messages in the words of the scene format. serde describes what it
//! wanted in Rust's terms (`f64`, `i64`, `a sequence`, `struct GridToml`) and names no field;
//! this file rewrites the type words into what a user writes (a number, a whole number, a list,
//! a table) and recovers the dotted key path that toml tracks but exposes only in its text.

/// The dotted path of the key a toml error is about (`grid.x`, `render.width`), when toml knows
/// it. toml keeps the path private and prints it (`in \`grid.x\``) only when the error carries
/// no input text, so a copy without the text is printed and the path read back from it.
pub(super) fn key_path(e: &toml::de::Error) -> Option<String> {
    let mut bare = e.clone();
    bare.set_input(None);
    let text = bare.to_string();
    let line = text.lines().rev().find(|l| l.starts_with("in `"))?;
    let path = line.strip_prefix("in `")?.strip_suffix('`')?;
    (!path.is_empty()).then(|| path.to_string())
}

/// `path` with the index of its array-of-tables entry: toml names `function.color`, and the
/// entry is the `[[function]]` header that last precedes the error at byte `offset`, so the
/// path becomes `function[2].color` (likewise for `[[key]]`).
pub(super) fn with_index(path: &str, text: &str, offset: usize) -> String {
    let (head, rest) = path.split_once('.').unwrap_or((path, ""));
    if !matches!(head, "function" | "key") {
        return path.to_string();
    }
    let header = format!("[[{head}]]");
    let before = &text[..offset.min(text.len())];
    let count = before.lines().filter(|l| l.trim_start().starts_with(&header)).count();
    if count == 0 {
        return path.to_string();
    }
    let indexed = format!("{head}[{}]", count - 1);
    if rest.is_empty() { indexed } else { format!("{indexed}.{rest}") }
}

/// A number as a user would write it: `1e300` rather than its 301 digits.
pub(super) fn show(x: f64) -> String {
    if x != 0.0 && x.is_finite() && !(1e-5..1e16).contains(&x.abs()) { format!("{x:e}") } else { format!("{x}") }
}

/// `message` with serde's type words replaced by the format's, e.g. `invalid type: string "1",
/// expected f64` → `expected a number, found the text "1"`.
pub(super) fn in_user_words(message: &str) -> String {
    let message = message.trim();
    for prefix in ["invalid type: ", "invalid value: "] {
        if let Some(rest) = message.strip_prefix(prefix)
            && let Some((found, expected)) = rest.rsplit_once(", expected ")
        {
            return format!("expected {}, found {}", expected_words(expected), found_words(found));
        }
    }
    if let Some(rest) = message.strip_prefix("invalid length ")
        && let Some((n, expected)) = rest.split_once(", expected ")
    {
        return format!("expected {}, found {n} elements", expected_words(expected));
    }
    message.to_string()
}

/// What serde expected, in the format's words.
fn expected_words(expected: &str) -> String {
    let expected = expected.trim();
    let word = match expected {
        "f64" | "f32" => "a number",
        "i64" | "i32" | "u64" | "u32" | "usize" | "u8" | "u16" | "i8" | "i16" => "a whole number",
        "a sequence" => "a list [..]",
        "a boolean" => "true or false",
        "a string" => "text in quotes",
        "a map" => "a table",
        _ if expected.starts_with("struct ") || expected.starts_with("a struct") => "a table",
        _ => return expected.to_string(),
    };
    word.to_string()
}

/// What serde found, in the format's words: `string "1"` → `the text "1"`, ``integer `5` `` →
/// `the whole number 5`.
fn found_words(found: &str) -> String {
    let found = found.trim();
    let inner = |s: &str| s.trim().trim_matches('`').to_string();
    if let Some(s) = found.strip_prefix("string ") {
        return format!("the text {}", s.trim());
    }
    if let Some(s) = found.strip_prefix("integer ") {
        return format!("the whole number {}", inner(s));
    }
    if let Some(s) = found.strip_prefix("floating point ") {
        // serde prints every digit (1e300 as 301 of them); a long number is shown as 1e300.
        let text = inner(s);
        return match text.parse::<f64>() {
            Ok(x) => format!("the number {}", show(x)),
            _ => format!("the number {text}"),
        };
    }
    if let Some(s) = found.strip_prefix("boolean ") {
        return inner(s);
    }
    match found {
        "sequence" => "a list".into(),
        "map" => "a table".into(),
        _ => found.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_entries_get_their_index() {
        let text = "[[function]]\nkind = 1\n[[function]]\ncolor = 5\n";
        assert_eq!(with_index("function.color", text, text.find("5").unwrap()), "function[1].color");
        assert_eq!(with_index("grid.x", text, 3), "grid.x");
    }

    #[test]
    fn type_words_become_format_words() {
        assert_eq!(
            in_user_words("invalid type: string \"1\", expected f64"),
            "expected a number, found the text \"1\""
        );
        assert_eq!(
            in_user_words("invalid type: integer `5`, expected struct GridToml"),
            "expected a table, found the whole number 5"
        );
        assert_eq!(in_user_words("invalid type: sequence, expected i64"), "expected a whole number, found a list");
        assert_eq!(in_user_words("missing field `x`"), "missing field `x`");
        assert_eq!(
            in_user_words(&format!("invalid type: floating point `{:?}`, expected i64", -1e300)),
            "expected a whole number, found the number -1e300"
        );
    }
}
