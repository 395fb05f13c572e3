//! The `modules` list of a model file, which holds modules written in RON and modules taken
//! from GenoM3 `.gen` files: `Gen("rflex.gen")` or `Gen(file: "ndd.gen", include: ["idl/"])`.
//!
//! serde reads the list while it reads the file, before the model's `tick_ms` (which the
//! `.gen` periods need) is known, and without the file's directory. So the list keeps its
//! RON modules and notes each `.gen` entry, with the place it takes among them, for
//! [`super::resolve`] to read once the whole model is parsed.

use std::cell::RefCell;
use std::fmt;

use serde::de::value::{MapAccessDeserializer, SeqAccessDeserializer};
use serde::de::{self, Deserialize, DeserializeSeed, Deserializer, MapAccess, SeqAccess, Visitor};

use crate::diag::ModelError;
use crate::genom::syntax::ModuleDef;
use crate::source::{Span, Text};

/// A `Gen(...)` entry of a model's `modules`.
#[derive(Clone, Debug)]
pub struct GenEntry {
    /// How many RON modules come before it in the list.
    pub index: usize,
    /// The `.gen` file, relative to the model file.
    pub file: Text,
    /// Directories searched by `#include`, relative to the model file.
    pub include: Vec<Text>,
}

thread_local! {
    static ENTRIES: RefCell<Option<Vec<GenEntry>>> = const { RefCell::new(None) };
}

/// Runs `f` (which deserializes a model) and returns the `.gen` entries its `modules` held.
pub(crate) fn collecting<R>(f: impl FnOnce() -> R) -> (R, Vec<GenEntry>) {
    struct Reset(Option<Vec<GenEntry>>);
    impl Drop for Reset {
        fn drop(&mut self) {
            let previous = self.0.take();
            ENTRIES.with(|cell| *cell.borrow_mut() = previous);
        }
    }
    let previous = ENTRIES.with(|cell| cell.borrow_mut().replace(Vec::new()));
    let reset = Reset(previous);
    let value = f();
    let entries = ENTRIES
        .with(|cell| cell.borrow_mut().take())
        .unwrap_or_default();
    drop(reset);
    (value, entries)
}

/// The `deserialize_with` of `SystemDef::modules`.
pub fn deserialize_modules<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<ModuleDef>, D::Error> {
    d.deserialize_seq(ListVisitor)
}

struct ListVisitor;

impl<'de> Visitor<'de> for ListVisitor {
    type Value = Vec<ModuleDef>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a list of modules: `(name: …)` or `Gen(\"file.gen\")`")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut modules = Vec::new();
        while let Some(entry) = seq.next_element_seed(EntrySeed {
            index: modules.len(),
        })? {
            if let Entry::Module(m) = entry {
                modules.push(*m);
            }
        }
        Ok(modules)
    }
}

enum Entry {
    Module(Box<ModuleDef>),
    Gen,
}

struct EntrySeed {
    index: usize,
}

impl<'de> DeserializeSeed<'de> for EntrySeed {
    type Value = Entry;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Entry, D::Error> {
        // `ron` reads a struct's name and drops it here: the shape tells the two apart
        d.deserialize_any(self)
    }
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct GenFields {
    file: Text,
    #[serde(default)]
    include: Vec<Text>,
}

impl EntrySeed {
    fn note<E: de::Error>(&self, fields: GenFields) -> Result<Entry, E> {
        let entry = GenEntry {
            index: self.index,
            file: fields.file,
            include: fields.include,
        };
        let noted = ENTRIES.with(|cell| match cell.borrow_mut().as_mut() {
            Some(list) => {
                list.push(entry);
                true
            }
            None => false,
        });
        if noted {
            Ok(Entry::Gen)
        } else {
            Err(E::custom(
                "`Gen(...)` modules are read by the model loader (bip_lang::load_file, load_str)",
            ))
        }
    }
}

impl<'de> Visitor<'de> for EntrySeed {
    type Value = Entry;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a module `(name: …)`, or `Gen(\"file.gen\")`, or `Gen(file: \"file.gen\", include: [\"dir/\"])`")
    }

    /// `Gen("rflex.gen")`.
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Entry, A::Error> {
        let (file,) = <(Text,)>::deserialize(SeqAccessDeserializer::new(seq))?;
        self.note(GenFields {
            file,
            include: Vec::new(),
        })
    }

    /// `(name: …)`, a module written in RON, or `Gen(file: …, include: …)`.
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Entry, A::Error> {
        let Some(first) = map.next_key::<String>()? else {
            return Err(de::Error::custom(
                "an empty module: it needs at least a `name`",
            ));
        };
        let rest = FirstKey {
            key: Some(first.clone()),
            map,
        };
        if first == "file" || first == "include" {
            let fields = GenFields::deserialize(MapAccessDeserializer::new(rest))?;
            return self.note(fields);
        }
        let module = ModuleDef::deserialize(MapAccessDeserializer::new(rest))?;
        Ok(Entry::Module(Box::new(module)))
    }
}

/// A map whose first key was already read.
struct FirstKey<A> {
    key: Option<String>,
    map: A,
}

impl<'de, A: MapAccess<'de>> MapAccess<'de> for FirstKey<A> {
    type Error = A::Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, A::Error> {
        match self.key.take() {
            Some(k) => seed
                .deserialize(de::value::StringDeserializer::<A::Error>::new(k))
                .map(Some),
            None => self.map.next_key_seed(seed),
        }
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, A::Error> {
        self.map.next_value_seed(seed)
    }
}

/// The error for an entry written `Other("x.gen")` rather than `Gen("x.gen")`: `ron` drops
/// the name before the entry's shape is seen, so it is read back from the model's text,
/// before the file's path.
pub(crate) fn misnamed(text: &str, entry: &GenEntry) -> Option<ModelError> {
    let before = text.get(..entry.file.span.start)?;
    // the opening quote, then `file:` if written, then `(`
    let mut rest = before.strip_suffix('"').unwrap_or(before).trim_end();
    if let Some(r) = rest.strip_suffix(':') {
        rest = r.trim_end().strip_suffix("file")?.trim_end();
    }
    rest = rest.strip_suffix('(')?.trim_end();
    let start = rest
        .rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .map_or(0, |i| i + 1);
    let word = &rest[start..];
    (word != "Gen").then(|| {
        let span = if word.is_empty() {
            entry.file.span
        } else {
            Span::new(start, rest.len())
        };
        ModelError::new(
            "a module from a GenoM3 file is written `Gen(\"file.gen\")`",
            span,
        )
        .with_help("or `Gen(file: \"file.gen\", include: [\"dir/\"])`")
    })
}
