//! Saving over a scene's own file: the new text is the file's TOML document edited in place
//! (with `toml_edit`), not a fresh one, so that a save keeps the file's comments, layout, the
//! order of its fields and tables, the spelling of every number it did not change
//! (`4_000_000`, `-40`) and leaves the defaults it did not set unset.
//!
//! Which values to change is decided on the scene and not on the text: the file is read as a
//! scene, both that scene and the scene to save are written out in full ([`Scene::to_toml`],
//! one spelling for one value), and the two full documents are compared key by key. Only where
//! they differ does the file's document change: a value is replaced (keeping the comments and
//! spaces around it), a missing field is added at the end of its table, a field or table the
//! new scene no longer has is removed, an added function or key is appended to its array of
//! tables, a deleted one is taken out with its comments. Arrays and inline tables of the same
//! length are compared element by element, so that moving one grid point rewrites one number.
//!
//! Some defaults depend on a function's place (an unnamed function is `f<i>`, an uncoloured
//! one takes the i-th palette colour), so the edited text is read back and compared with the
//! scene again; a few rounds make it exact. Should the text still not read back as the scene
//! (a file the comparison cannot follow), [`edit_over`] gives up and the caller writes the
//! scene in full: a save is always exact, and keeps the file's form wherever it can.

use toml_edit::{ArrayOfTables, DocumentMut, InlineTable, Item, Table, Value};

use crate::scene::Scene;

/// Rounds of compare, edit and read back before giving up: one for the edits, one for the
/// defaults that depend on a function's place, one to spare.
const MAX_ROUNDS: usize = 3;

/// `scene` as the TOML document `original` edited to hold it (see the module note); None
/// when `original` is not a scene or the edited text would not read back as `scene`.
pub(super) fn edit_over(scene: &Scene, original: &str) -> Option<String> {
    let mut doc: DocumentMut = original.parse().ok()?;
    let target: DocumentMut = scene.to_toml().parse().ok()?;
    let mut text = original.to_string();
    for round in 0..=MAX_ROUNDS {
        let current = Scene::parse(&text, "the scene file").ok()?;
        if same_scene(&current, scene) {
            return Some(text);
        }
        if round == MAX_ROUNDS {
            break;
        }
        let base: DocumentMut = current.to_toml().parse().ok()?;
        edit_table(doc.as_table_mut(), base.as_table(), target.as_table());
        text = doc.to_string();
    }
    None
}

/// Equal scenes wherever they were read from.
fn same_scene(a: &Scene, b: &Scene) -> bool {
    Scene { path: None, ..a.clone() } == Scene { path: None, ..b.clone() }
}

/// Edits `doc` (a table of the file) where `target` (the new scene's full table) differs from
/// `base` (the full table of what the file holds now).
fn edit_table(doc: &mut Table, base: &Table, target: &Table) {
    for (key, t) in target.iter() {
        let b = base.get(key);
        if b.is_some_and(|b| same_item(b, t)) {
            continue;
        }
        match doc.get_mut(key) {
            Some(d) => edit_item(d, b, t),
            None => {
                let item = match (b.and_then(Item::as_table), t) {
                    // A table the file leaves out (all defaults): only what changed goes in.
                    (Some(b), Item::Table(t)) => {
                        let mut table = Table::new();
                        table.decor_mut().set_prefix("\n");
                        edit_table(&mut table, b, t);
                        Item::Table(table)
                    }
                    _ => fresh(t),
                };
                doc.insert(key, item);
            }
        }
    }
    let gone: Vec<String> = base.iter().filter(|(k, _)| !target.contains_key(k)).map(|(k, _)| k.to_string()).collect();
    for key in gone {
        doc.remove(&key);
    }
}

fn edit_item(doc: &mut Item, base: Option<&Item>, target: &Item) {
    match (doc, target) {
        (Item::Table(d), Item::Table(t)) => {
            let empty = Table::new();
            edit_table(d, base.and_then(Item::as_table).unwrap_or(&empty), t);
        }
        (Item::ArrayOfTables(d), Item::ArrayOfTables(t)) => edit_tables(d, base.and_then(Item::as_array_of_tables), t),
        (Item::Value(d), Item::Value(t)) => edit_value(d, base.and_then(Item::as_value), t),
        // Another shape (an inline table where the writer writes a table): written anew.
        (d, t) => *d = fresh(t),
    }
}

fn edit_value(doc: &mut Value, base: Option<&Value>, target: &Value) {
    if base.is_some_and(|b| same_value(b, target)) {
        return;
    }
    match (doc, base, target) {
        (Value::Array(d), Some(Value::Array(b)), Value::Array(t)) if d.len() == b.len() && b.len() == t.len() => {
            for (i, t) in t.iter().enumerate() {
                if let Some(d) = d.get_mut(i) {
                    edit_value(d, b.get(i), t);
                }
            }
        }
        (Value::InlineTable(d), Some(Value::InlineTable(b)), Value::InlineTable(t)) => edit_inline(d, b, t),
        (d, _, t) => replace_value(d, t),
    }
}

/// [`edit_table`] for an inline table (a builder's step).
fn edit_inline(doc: &mut InlineTable, base: &InlineTable, target: &InlineTable) {
    for (key, t) in target.iter() {
        let b = base.get(key);
        if b.is_some_and(|b| same_value(b, t)) {
            continue;
        }
        match doc.get_mut(key) {
            Some(d) => edit_value(d, b, t),
            None => {
                // The new field goes last, taking over the space before the closing brace.
                let mut value = t.clone();
                let before_brace = doc.iter_mut().last().map(|(_, v)| {
                    let suffix = v.decor().suffix().and_then(|s| s.as_str()).unwrap_or("").to_string();
                    v.decor_mut().set_suffix("");
                    suffix
                });
                value.decor_mut().set_prefix(" ");
                value.decor_mut().set_suffix(before_brace.unwrap_or_else(|| " ".into()));
                doc.insert(key, value);
            }
        }
    }
    let gone: Vec<String> = base.iter().filter(|(k, _)| !target.contains_key(k)).map(|(k, _)| k.to_string()).collect();
    for key in gone {
        doc.remove(&key);
    }
}

/// Puts `target` in `doc`'s place, keeping the comments and spaces around it, and an integer's
/// digit grouping (`4_000_000`) where the file grouped it.
fn replace_value(doc: &mut Value, target: &Value) {
    let decor = doc.decor().clone();
    let grouped = matches!(doc, Value::Integer(i) if i.display_repr().contains('_'));
    let mut value = match target {
        Value::Integer(t) if grouped => group_digits(*t.value()).parse().unwrap_or_else(|_| target.clone()),
        _ => target.clone(),
    };
    *value.decor_mut() = decor;
    *doc = value;
}

/// An integer with `_` between groups of three digits.
fn group_digits(n: i64) -> String {
    let digits = n.unsigned_abs().to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push('_');
        }
        out.push(c);
    }
    if n < 0 { format!("-{out}") } else { out }
}

/// Edits an array of tables (functions, keys, a key's functions): each table of the file is
/// paired with the table of the new scene it became (by name, or by time for keys); the paired
/// ones are edited, the others removed, new ones added in their place.
fn edit_tables(doc: &mut ArrayOfTables, base: Option<&ArrayOfTables>, target: &ArrayOfTables) {
    let Some(base) = base else {
        *doc = fresh_tables(target);
        return;
    };
    let base: Vec<&Table> = base.iter().collect();
    let target_tables: Vec<&Table> = target.iter().collect();
    let Some(doc_to_base) = correspond(doc, &base) else {
        *doc = fresh_tables(target);
        return;
    };
    let base_to_target = align(&base, &target_tables);
    let mut doc_of_target = vec![None; target_tables.len()];
    for (d, &b) in doc_to_base.iter().enumerate() {
        if let Some(t) = base_to_target[b] {
            doc_of_target[t] = Some(d);
        }
    }
    // The file's tables keep their order in the text: a save that would reorder them writes
    // the whole array anew instead.
    let kept: Vec<usize> = doc_of_target.iter().flatten().copied().collect();
    if !kept.is_sorted() {
        *doc = fresh_tables(target);
        return;
    }
    let mut old: Vec<Option<Table>> = doc.iter().cloned().map(Some).collect();
    let mut out = ArrayOfTables::new();
    for (t, target_table) in target_tables.iter().enumerate() {
        match doc_of_target[t].and_then(|d| old[d].take().map(|table| (d, table))) {
            Some((d, mut table)) => {
                edit_table(&mut table, base[doc_to_base[d]], target_table);
                out.push(table);
            }
            None => {
                if let Item::Table(table) = fresh(&Item::Table((*target_table).clone())) {
                    out.push(table);
                }
            }
        }
    }
    *doc = out;
}

/// What identifies a table of an array: a function's name, a key's time.
fn ident(table: &Table) -> Option<String> {
    if let Some(name) = table.get("name").and_then(Item::as_str) {
        return Some(format!("name {name}"));
    }
    let t = table.get("t_secs")?;
    let t = t.as_float().or_else(|| t.as_integer().map(|i| i as f64))?;
    Some(format!("t {t:?}"))
}

/// The base table each of the file's tables reads as: the same place when the names agree
/// (a table without a name is the one in its place), else the one of the same name.
fn correspond(doc: &ArrayOfTables, base: &[&Table]) -> Option<Vec<usize>> {
    if doc.len() != base.len() {
        return None;
    }
    let doc_ids: Vec<Option<String>> = doc.iter().map(ident).collect();
    let base_ids: Vec<Option<String>> = base.iter().map(|t| ident(t)).collect();
    if doc_ids.iter().zip(&base_ids).all(|(d, b)| d.is_none() || d == b) {
        return Some((0..doc.len()).collect());
    }
    // Another order (a key's functions are read sorted by function): by name, each once.
    let mut used = vec![false; base.len()];
    let mut out = Vec::with_capacity(doc.len());
    for id in &doc_ids {
        let id = id.as_ref()?;
        let b = base_ids.iter().enumerate().position(|(b, bid)| !used[b] && bid.as_ref() == Some(id))?;
        used[b] = true;
        out.push(b);
    }
    Some(out)
}

/// For each base table, the target table it became: the longest common run of identities
/// pairs tables, and the tables between two paired ones pair in order (an edited or renamed
/// one); the rest were deleted (base) or added (target).
fn align(base: &[&Table], target: &[&Table]) -> Vec<Option<usize>> {
    let b: Vec<Option<String>> = base.iter().map(|t| ident(t)).collect();
    let t: Vec<Option<String>> = target.iter().map(|t| ident(t)).collect();
    let (n, m) = (b.len(), t.len());
    let matches = |i: usize, j: usize| b[i].is_some() && b[i] == t[j];
    // lcs[i][j]: the longest common subsequence of b[i..] and t[j..].
    let mut lcs = vec![vec![0u32; m + 1]; n + 1];
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            lcs[i][j] = if matches(i, j) { lcs[i + 1][j + 1] + 1 } else { lcs[i + 1][j].max(lcs[i][j + 1]) };
        }
    }
    let mut out = vec![None; n];
    let (mut gap_b, mut gap_t) = (Vec::new(), Vec::new());
    let flush = |gap_b: &mut Vec<usize>, gap_t: &mut Vec<usize>, out: &mut Vec<Option<usize>>| {
        for (&i, &j) in gap_b.iter().zip(gap_t.iter()) {
            out[i] = Some(j);
        }
        gap_b.clear();
        gap_t.clear();
    };
    let (mut i, mut j) = (0, 0);
    while i < n && j < m {
        if matches(i, j) {
            flush(&mut gap_b, &mut gap_t, &mut out);
            out[i] = Some(j);
            i += 1;
            j += 1;
        } else if lcs[i + 1][j] >= lcs[i][j + 1] {
            gap_b.push(i);
            i += 1;
        } else {
            gap_t.push(j);
            j += 1;
        }
    }
    gap_b.extend(i..n);
    gap_t.extend(j..m);
    flush(&mut gap_b, &mut gap_t, &mut out);
    out
}

/// A copy of the writer's `item` for the file: its tables take their place in the file's
/// order from where they are put (not from the writer's text).
fn fresh(item: &Item) -> Item {
    let mut item = item.clone();
    unplace(&mut item);
    item
}

fn fresh_tables(tables: &ArrayOfTables) -> ArrayOfTables {
    let mut out = tables.clone();
    out.iter_mut().for_each(unplace_table);
    out
}

fn unplace(item: &mut Item) {
    match item {
        Item::Table(t) => unplace_table(t),
        Item::ArrayOfTables(a) => a.iter_mut().for_each(unplace_table),
        _ => {}
    }
}

fn unplace_table(table: &mut Table) {
    table.set_position(None);
    for (_, item) in table.iter_mut() {
        unplace(item);
    }
}

/// The same TOML value, however spelled.
fn same_value(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::String(x), Value::String(y)) => x.value() == y.value(),
        (Value::Integer(x), Value::Integer(y)) => x.value() == y.value(),
        (Value::Float(x), Value::Float(y)) => x.value() == y.value(),
        (Value::Boolean(x), Value::Boolean(y)) => x.value() == y.value(),
        (Value::Datetime(x), Value::Datetime(y)) => x.value() == y.value(),
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y.iter()).all(|(p, q)| same_value(p, q))
        }
        (Value::InlineTable(x), Value::InlineTable(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same_value(v, w)))
        }
        _ => false,
    }
}

fn same_item(a: &Item, b: &Item) -> bool {
    match (a, b) {
        (Item::Value(x), Item::Value(y)) => same_value(x, y),
        (Item::Table(x), Item::Table(y)) => same_table(x, y),
        (Item::ArrayOfTables(x), Item::ArrayOfTables(y)) => {
            x.len() == y.len() && x.iter().zip(y.iter()).all(|(p, q)| same_table(p, q))
        }
        (Item::None, Item::None) => true,
        _ => false,
    }
}

fn same_table(a: &Table, b: &Table) -> bool {
    a.len() == b.len() && a.iter().all(|(k, v)| b.get(k).is_some_and(|w| same_item(v, w)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digits_are_grouped_in_threes() {
        assert_eq!(group_digits(4_000_000), "4_000_000");
        assert_eq!(group_digits(12_345), "12_345");
        assert_eq!(group_digits(999), "999");
        assert_eq!(group_digits(-1_000), "-1_000");
    }
}
