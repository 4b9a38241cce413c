//! A report's scenes split over the tasks of a job array (`--task I/N`), and the combined report
//! written from their folders once every task is done (`--combine`).
//!
//! The unit of the split is the scene. A scene's configurations are timed against its own uniform
//! render, so they stay on one machine: their speed-ups compare run times of the same hardware. A
//! scene's reference, the long part, splits by samples instead (`--reference-part`,
//! docs/cluster.md).
use std::path::{Path, PathBuf};

use crate::error::{FoveaError, Result};
use crate::values::ArrayTask;

/// One scene of a report: its file (None: the bundled default) and its output folder.
pub type SceneEntry = (Option<PathBuf>, PathBuf);

/// The heading every report.md starts with.
pub const HEADING: &str = "# Error against run time (`fovea report`)\n\n";

/// The scenes `task` measures: every `N`-th from the `I`-th. A task that would get none is refused
/// (an array larger than the scene list is a mistake in the job script).
pub fn scenes_of_task(scenes: &[SceneEntry], task: ArrayTask) -> Result<Vec<SceneEntry>> {
    let [index, count] = task.0;
    if count as usize > scenes.len() {
        return Err(FoveaError::option(
            "--task",
            format!(
                "{index}/{count}: there are {} scene(s), so some of the {count} tasks would measure \
                 nothing; use N <= {}",
                scenes.len(),
                scenes.len()
            ),
        ));
    }
    Ok(scenes
        .iter()
        .enumerate()
        .filter(|(i, _)| task.takes(*i))
        .map(|(_, s)| s.clone())
        .collect())
}

/// The combined report.md of several scenes under `out`: each scene's section (`sections`: its folder
/// and its report.md without the heading), its reference image named by its folder, then the scenes
/// that failed (`failures`: name and error).
#[must_use]
pub fn combined_markdown(
    out: &Path,
    sections: &[(PathBuf, String)],
    failures: &[(String, String)],
) -> String {
    let mut text = String::from(HEADING);
    for (dir, md) in sections {
        let rel = dir.strip_prefix(out).unwrap_or(dir);
        text.push_str(&md.replace(
            "`reference.png`",
            &format!("`{}/reference.png`", rel.display()),
        ));
        text.push('\n');
    }
    for (name, e) in failures {
        text.push_str(&format!("## {name}: failed\n\n{e}\n\n"));
    }
    text
}

/// Each scene's section, read back from its folder for `--combine`: its report.md without the
/// heading. Every scene must have one, and its report.json must name the same scene file (a folder
/// left from another report is refused). The error lists every scene still missing.
pub fn read_sections(scenes: &[SceneEntry]) -> Result<Vec<(PathBuf, String)>> {
    let mut sections = Vec::new();
    let mut missing = Vec::new();
    for (i, (scene, dir)) in scenes.iter().enumerate() {
        let (md_path, json_path) = (dir.join("report.md"), dir.join("report.json"));
        let (Ok(md), Ok(json)) = (
            std::fs::read_to_string(&md_path),
            std::fs::read_to_string(&json_path),
        ) else {
            missing.push(format!("scene {i} ({})", dir.display()));
            continue;
        };
        let json: serde_json::Value = serde_json::from_str(&json)
            .map_err(|e| FoveaError::file(&json_path, format!("is not a report's JSON: {e}")))?;
        if let Some(scene) = scene {
            let named = json["scene"].as_str().unwrap_or("no scene");
            if Path::new(named) != scene.as_path() {
                return Err(FoveaError::file(
                    &json_path,
                    format!(
                        "is the report of '{named}', not of '{}': remove the folder and run its \
                         task again",
                        scene.display()
                    ),
                ));
            }
        }
        let section = md.strip_prefix(HEADING).ok_or_else(|| {
            FoveaError::file(&md_path, "does not start with a fovea report's heading")
        })?;
        sections.push((dir.clone(), section.to_owned()));
    }
    if !missing.is_empty() {
        return Err(FoveaError::option(
            "--combine",
            format!(
                "{} of {} scenes have no report yet: {}. Scene k is measured by the task k mod N of \
                 --task I/N; run those tasks again, then combine; nothing was written",
                missing.len(),
                scenes.len(),
                missing.join(", ")
            ),
        ));
    }
    Ok(sections)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenes(n: usize) -> Vec<SceneEntry> {
        (0..n)
            .map(|i| {
                (
                    Some(PathBuf::from(format!("s{i}.obj"))),
                    PathBuf::from(format!("out/s{i}")),
                )
            })
            .collect()
    }

    #[test]
    fn tasks_tile_the_scenes_and_an_empty_task_is_refused() {
        let all = scenes(5);
        let mut seen = Vec::new();
        for i in 0..2 {
            let task: ArrayTask = format!("{i}/2").parse().unwrap();
            seen.extend(scenes_of_task(&all, task).unwrap());
        }
        seen.sort();
        assert_eq!(seen, all);
        let too_many: ArrayTask = "0/6".parse().unwrap();
        let e = scenes_of_task(&all, too_many).unwrap_err().to_string();
        assert!(
            e.contains("there are 5 scene(s)") && e.contains("N <= 5"),
            "{e}"
        );
        assert!("2/2".parse::<ArrayTask>().is_err());
        assert!("-1/2".parse::<ArrayTask>().is_err());
    }
}
