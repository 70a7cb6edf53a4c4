//! What a behaviour's settings are, for the people who write scenario files.
//!
//! Registering a behaviour registers its config's [`Describe`] too, so that
//! `ubf behaviors --describe` and the tables in the scenario format's docs
//! come from one place (a test holds the docs to it).

use crate::config::Checked;
use serde::Serialize;

/// One field of a behaviour's config.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Field {
    /// The name written in a scenario file.
    pub name: &'static str,
    /// What kind of value it takes: `number`, `whole number`, `bool`,
    /// `text`, or the name of a structured setting.
    pub kind: &'static str,
    /// Its unit (`m/s`, `°`), or empty.
    pub unit: &'static str,
    /// Its default as written in a scenario file, or `required`.
    pub default: &'static str,
    /// The values accepted (`> 0`, `0 to 1`), or empty for any of its kind.
    pub range: &'static str,
    /// What it does.
    pub meaning: &'static str,
}

impl Field {
    /// A field: name, kind, unit, default (`required` if none), range and
    /// meaning.
    pub const fn new(
        name: &'static str,
        kind: &'static str,
        unit: &'static str,
        default: &'static str,
        range: &'static str,
        meaning: &'static str,
    ) -> Field {
        Field { name, kind, unit, default, range, meaning }
    }

    /// Whether a scenario file must give it.
    pub fn required(&self) -> bool {
        self.default == "required"
    }
}

/// A behaviour config that can say what its fields are. Registering a
/// behaviour needs it; a behaviour without settings returns no fields.
///
/// ```
/// use ubf_core::{Describe, Field};
///
/// struct CruiseConfig { speed: f64 }
///
/// impl Describe for CruiseConfig {
///     fn fields() -> Vec<Field> {
///         vec![Field::new("speed", "number", "m/s", "0.5", "> 0", "forward speed")]
///     }
/// }
/// assert_eq!(CruiseConfig::fields()[0].unit, "m/s");
/// ```
pub trait Describe {
    /// The fields, in the order the docs list them.
    fn fields() -> Vec<Field>;
}

impl<T: Describe> Describe for Checked<T> {
    fn fields() -> Vec<Field> {
        T::fields()
    }
}

/// The fields as the Markdown table the scenario format's docs show:
/// field, kind, unit, default, range, meaning (`—` for an empty cell).
pub fn markdown_table(fields: &[Field]) -> String {
    let cell = |text: &str| if text.is_empty() { "—".to_owned() } else { text.replace('|', "\\|") };
    let code = |text: &str| if text == "required" { text.to_owned() } else { format!("`{text}`") };
    let mut out =
        String::from("| field | kind | unit | default | range | meaning |\n| --- | --- | --- | --- | --- | --- |\n");
    for f in fields {
        out.push_str(&format!(
            "| `{}` | {} | {} | {} | {} | {} |\n",
            f.name,
            cell(f.kind),
            cell(f.unit),
            code(f.default),
            cell(f.range),
            cell(f.meaning)
        ));
    }
    out
}
