//! Opening problems: a path field, the problems shipped in
//! `scenes/problems/`, and the recent files.

use std::path::{Path, PathBuf};

use eframe::egui;

use crate::app::ViewerApp;

/// The shipped problems folder: `scenes/problems` under the working
/// directory, else the one of the source tree this binary was built from.
pub fn problem_dir() -> Option<PathBuf> {
    let here = PathBuf::from("scenes/problems");
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/problems");
    [here, built].into_iter().find(|d| d.is_dir())
}

/// The `.toml` files of `dir` (the extension in any case), sorted.
fn problems_in(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.extension()
                        .is_some_and(|x| x.eq_ignore_ascii_case("toml"))
                })
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

/// Draws the open section.
pub fn show(ui: &mut egui::Ui, app: &mut ViewerApp) {
    let mut chosen = None;
    ui.horizontal(|ui| {
        let label = ui.label("Path:");
        let field = ui
            .add(
                egui::TextEdit::singleline(&mut app.controls.path_text)
                    .hint_text("problem.toml")
                    .desired_width(200.0),
            )
            .labelled_by(label.id);
        let enter = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        if (ui.button("Open").clicked() || enter) && !app.controls.path_text.trim().is_empty() {
            chosen = Some(PathBuf::from(app.controls.path_text.trim()));
        }
    });
    if let Some(dir) = problem_dir() {
        ui.label("Shipped problems:");
        ui.horizontal_wrapped(|ui| {
            for f in problems_in(&dir) {
                let name = f.file_stem().map(|s| s.to_string_lossy().into_owned());
                if ui.button(name.unwrap_or_default()).clicked() {
                    chosen = Some(f);
                }
            }
        });
    }
    if !app.recent.files.is_empty() {
        ui.label("Recent:");
        let cwd = std::env::current_dir().unwrap_or_default();
        for f in app.recent.files.clone() {
            let shown = f.strip_prefix(&cwd).unwrap_or(&f).display().to_string();
            if ui.link(shown).clicked() {
                chosen = Some(f);
            }
        }
    }
    if let Some(p) = chosen {
        app.open(p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn problems_are_the_toml_files_in_any_case_sorted() {
        let dir = tempfile::tempdir().expect("temp dir");
        for name in ["b.toml", "A.TOML", "c.Toml", "d.txt", "toml", "e.toml.bak"] {
            std::fs::write(dir.path().join(name), "").expect("write");
        }
        let names: Vec<_> = problems_in(dir.path())
            .iter()
            .map(|p| {
                p.file_name()
                    .expect("a name")
                    .to_string_lossy()
                    .into_owned()
            })
            .collect();
        assert_eq!(names, ["A.TOML", "b.toml", "c.Toml"]);
    }
}
