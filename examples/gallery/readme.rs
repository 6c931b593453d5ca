//! The README's gallery table: where it lies, what it says (and the day it was made),
//! how it is replaced. tests/gallery.rs reads this file too.

use super::entries::{Entry, GALLERY_SPP};

/// The README's gallery lies between these two lines; the gallery tool rewrites it.
pub const README_START: &str =
    "<!-- gallery: written by `cargo run --release --example gallery`; do not edit -->";
pub const README_END: &str = "<!-- end of gallery -->";

/// A rendered gallery image, for the table.
#[derive(Debug, Clone)]
pub struct Rendered {
    pub entry: Entry,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seconds: f64,
    /// The adapter that rendered it.
    pub device: String,
    /// Samples dropped as not finite (there should be none).
    pub non_finite: u64,
}

/// The README's gallery block: a paragraph on how and when it was made (`date`) and one
/// table row per image, `image_dir` being the images' folder relative to the README.
pub fn readme_block(rendered: &[Rendered], device: &str, date: &str, image_dir: &str) -> String {
    let mut s = format!(
        "{README_START}\n\nMade on {date} by `cargo run --release --example gallery` (from the \
         repository root) on {device}: each scene at its own size, {GALLERY_SPP} samples per \
         pixel unless the table says otherwise; seconds of rendering, after a one-sample render \
         that compiles the shader.\n\n\
         | image | shows | scene | size, spp | seconds |\n|---|---|---|---|---|\n"
    );
    for r in rendered {
        let e = &r.entry;
        let sampler = match e.sampler {
            Some(kind) => format!(" `--sampler {}`", kind.name()),
            None => String::new(),
        };
        s += &format!(
            "| <img src=\"{image_dir}/{}.png\" width=\"240\" alt=\"{}\"> | {} | [{}]({}){sampler} \
             | {} x {}, {} | {:.1} |\n",
            e.name, e.shows, e.shows, e.scene, e.scene, r.width, r.height, r.spp, r.seconds
        );
    }
    s + "\n" + README_END
}

/// `readme` with its gallery block (from [`README_START`] to [`README_END`]) replaced by
/// `block`; an error when the markers are missing or out of order.
pub fn replace_block(readme: &str, block: &str) -> Result<String, String> {
    let start = readme
        .find(README_START)
        .ok_or_else(|| format!("no line `{README_START}`"))?;
    let end = readme[start..]
        .find(README_END)
        .map(|i| start + i + README_END.len())
        .ok_or_else(|| format!("no line `{README_END}` after `{README_START}`"))?;
    Ok(format!("{}{block}{}", &readme[..start], &readme[end..]))
}
