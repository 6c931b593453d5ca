//! Mitsuba 3 scene files in: `parse` reads a file into a tree of plugins with every value
//! parsed and every position kept; `import` maps the tree onto wgtrace's scene format as
//! TOML text whose tables remember the elements they came from; `spectrum` turns spectra
//! into RGB as Mitsuba's RGB mode does (with `cie`'s tables) and knows the named indices
//! of refraction.

mod cie;
pub mod import;
pub mod parse;
pub mod spectrum;

pub use import::{import, Imported, Origin};
pub use parse::{
    parse_file, parse_str, snake_case, Object, Pos, Property, SceneTree, Spectrum, Value, XmlError,
};
