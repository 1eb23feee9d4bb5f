//! Every TOML block of the documentation (docs/*.md and the README) is a scene that loads and
//! renders as written (issue 30, item 9: the walkthrough's only block failed with "no material
//! named `clay`"). Relative file names in the blocks are read from `scenes/`, where the bundled
//! examples' meshes and textures are, as the docs say.

use caustic::options::Options;
use std::path::Path;

/// The ```toml blocks of a markdown text, with the line each starts on.
fn toml_blocks(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        match (&mut current, line.trim_start()) {
            (None, l) if l.starts_with("```toml") => current = Some((i + 1, String::new())),
            (Some(_), l) if l.starts_with("```") => out.push(current.take().unwrap()),
            (Some((_, body)), _) => {
                body.push_str(line);
                body.push('\n');
            }
            (None, _) => {}
        }
    }
    out
}

#[test]
fn every_toml_block_in_the_docs_renders() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    files.push(root.join("README.md"));
    files.sort();
    let small = Options { width: Some(16), height: Some(12), spp: Some(1), ..Default::default() };
    let mut rendered = 0;
    let mut failures = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for (line, block) in toml_blocks(&text) {
            let name = format!("{}:{line}", file.file_name().unwrap().to_string_lossy());
            match caustic::app::load_toml_str(&block, &name, &root.join("scenes"), &small) {
                Ok(scene) => {
                    let image = scene.render().image;
                    assert!(image.pixels.iter().all(|p| p.is_finite()), "{name}: non-finite pixels");
                    rendered += 1;
                }
                Err(e) => failures.push(format!("{name}: {e}")),
            }
        }
    }
    assert!(failures.is_empty(), "documentation blocks that do not render:\n{}", failures.join("\n"));
    assert!(rendered >= 11, "only {rendered} blocks found");
}
