//! Writes a `.fmu` archive: modelDescription.xml, the generic binary of each platform under
//! the model identifier, the scene in `resources/`, the documentation and the icon `model.png`.

use std::io::Write;
use std::path::Path;

use zip::write::SimpleFileOptions;

use super::description::{
    generation_tool, iso8601_utc, model_description, model_identifier, Provenance,
};
use super::documentation::index_html;
use super::guid_for;
use super::platforms::{from_these_sources, Binary, LINUX64};
use super::variables::VariableTable;
use crate::partial::Partial;
use crate::render::{self, picture, Frames};
use crate::scene::Scene;
use crate::sim::Simulation;

/// The interactive viewer of the structure, linked from `documentation/index.html`.
pub const STRUCTURE_PAGE: &str = "documentation/structure.html";

/// What [`build_fmu`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Built {
    /// The GUID in modelDescription.xml.
    pub guid: String,
    /// The model identifier (binary name).
    pub model_identifier: String,
    /// Number of variables.
    pub variables: usize,
    /// The equilibrium solve, when the scene starts at its equilibrium.
    pub start: Option<crate::model::StartReport>,
    /// Why the FMU, at the scene's own settings and start inputs, refuses its first
    /// `fmi2DoStep` (the stability guard's message), if it does.
    pub unstable: Option<String>,
    /// Why the scene's own fixed step, though stable, cannot follow its fastest mode.
    pub inaccurate: Option<String>,
}

/// The GUID placeholder of the golden modelDescription files (the real GUID hashes the
/// binary, so it changes with every code change).
pub const GOLDEN_GUID: &str = "{00000000-0000-0000-0000-000000000000}";

/// The provenance of the golden files: [`GOLDEN_GUID`], commit `0000000` and the epoch,
/// in place of what varies from build to build.
pub fn golden_provenance() -> Provenance {
    Provenance {
        guid: GOLDEN_GUID.to_string(),
        generation_tool: generation_tool("0000000"),
        generation_date_and_time: iso8601_utc(0),
    }
}

/// modelDescription.xml of `scene` as packaged, but with [`golden_provenance`]: the golden
/// files under `modelDescription/` hold this text for each shipped scene.
pub fn golden_model_description(scene: &Scene) -> Result<String, String> {
    let model = crate::analysis::load(scene).map_err(|e| e.to_string())?;
    let sim = Simulation::new(model);
    let table = VariableTable::new(&sim);
    model_description(sim.model(), &table, &golden_provenance())
        .to_xml()
        .map_err(|e| format!("modelDescription.xml: {e}"))
}

/// Builds the FMU for `scene` at `out`, with the linux64 shared library at `binary`.
pub fn build_fmu(scene: &Scene, binary: &Path, out: &Path) -> Result<Built, String> {
    let binary = Binary {
        platform: LINUX64,
        path: binary.to_path_buf(),
    };
    build_fmu_for(scene, &[binary], out)
}

/// Builds the FMU for `scene` at `out` with these binaries (one per platform; the same
/// modelDescription.xml for all).
pub fn build_fmu_for(scene: &Scene, binaries: &[Binary], out: &Path) -> Result<Built, String> {
    let scene_text = scene.to_toml_string();
    let model = crate::analysis::load(scene).map_err(|e| e.to_string())?;
    let mut sim = Simulation::new(model);
    if let Some(why) = sim.step_size_problem() {
        return Err(why);
    }
    let unstable = sim.stability_problem();
    let inaccurate = sim.accuracy_problem();
    let table = VariableTable::new(&sim);
    let guid = guid_for(&scene_text);
    let description = model_description(sim.model(), &table, &Provenance::current(guid.clone()));
    let xml = description
        .to_xml()
        .map_err(|e| format!("modelDescription.xml: {e}"))?;
    let id = model_identifier(sim.model());
    let mut libraries = Vec::new();
    for Binary { platform, path } in binaries {
        let bytes = std::fs::read(path)
            .map_err(|e| format!("cannot read the FMU binary {}: {e}", path.display()))?;
        // The binary hashes the same BUILD_ID into the GUID; a stale one could never load.
        if !from_these_sources(&bytes) {
            return Err(format!(
                "the FMU binary {} was built from other sources than this program (its GUIDs \
                 would not match); rebuild both with `cargo build --release --workspace` and \
                 `bash fmu/build-binary.sh`",
                path.display()
            ));
        }
        let name = format!("binaries/{}/{id}.{}", platform.folder, platform.extension);
        libraries.push((name, bytes));
    }
    let file_name = out.file_name().map_or_else(
        || format!("{}.fmu", sim.model().scene.name),
        |name| name.to_string_lossy().into_owned(),
    );
    let html = index_html(&sim, &table, &file_name);
    // The FMI 2.0 icon and the documentation's viewer: the structure at its start.
    let start = sim.time();
    let at_start = Frames::record(&mut sim, &[start])?;
    let icon = picture::icon_png(&at_start)?;
    let viewer = render::html::page(&at_start);
    let mut entries: Vec<(String, &[u8])> = vec![("modelDescription.xml".into(), xml.as_bytes())];
    entries.extend(libraries.iter().map(|(n, b)| (n.clone(), b.as_slice())));
    entries.extend([
        ("resources/scene.toml".into(), scene_text.as_bytes()),
        ("documentation/index.html".into(), html.as_bytes()),
        (STRUCTURE_PAGE.into(), viewer.as_bytes()),
        ("model.png".into(), icon.as_slice()),
    ]);
    write_atomically(out, &entries)?;
    Ok(Built {
        guid,
        model_identifier: id,
        variables: table.variables.len(),
        start: sim.model().start,
        unstable,
        inaccurate,
    })
}

/// Writes the archive whole or not at all (see [`Partial`]), so a failure never leaves a
/// partial `.fmu` nor clobbers an existing one.
fn write_atomically(out: &Path, entries: &[(String, &[u8])]) -> Result<(), String> {
    let (partial, file) = Partial::create(out)?;
    write_zip(file, out, entries)?;
    partial.commit()
}

fn write_zip(file: std::fs::File, path: &Path, entries: &[(String, &[u8])]) -> Result<(), String> {
    let failed = |e: &dyn std::fmt::Display| format!("writing {}: {e}", path.display());
    let mut zip = zip::ZipWriter::new(file);
    let options = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    for (name, data) in entries {
        zip.start_file(name.as_str(), options)
            .map_err(|e| failed(&format!("{name}: {e}")))?;
        zip.write_all(data)
            .map_err(|e| failed(&format!("{name}: {e}")))?;
    }
    zip.finish().map_err(|e| failed(&e))?;
    Ok(())
}
