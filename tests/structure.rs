//! The shape of the code: no two top-level modules import each other, directly or in a
//! circle, so each can be read (and given its GPU twin) without the ones above it; `dof` and
//! `motion` are siblings that never import each other. Test-only code (after `#[cfg(test)]`)
//! is left out, as dev-dependencies are.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The top-level module each source file of `src/` belongs to, and the top-level modules its
/// non-test code names through `crate::`.
fn imports() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut stack = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let relative = path.strip_prefix(&src).unwrap();
            let module = relative
                .iter()
                .next()
                .unwrap()
                .to_string_lossy()
                .trim_end_matches(".rs")
                .to_string();
            if ["lib", "main"].contains(&module.as_str()) {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            // Code only: comments may name any module, and tests are left out.
            let code: String = text
                .split("#[cfg(test)]")
                .next()
                .unwrap()
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect::<Vec<_>>()
                .join("\n");
            let uses = graph.entry(module.clone()).or_default();
            for (i, _) in code.match_indices("crate::") {
                let name: String = code[i + 7..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() && name != module {
                    uses.insert(name);
                }
            }
        }
    }
    graph
}

#[test]
fn dof_and_motion_do_not_import_each_other() {
    let graph = imports();
    assert!(!graph["dof"].contains("motion"), "{:?}", graph["dof"]);
    assert!(!graph["motion"].contains("dof"), "{:?}", graph["motion"]);
    // The effects stand on frames and the numeric policy alone (the lab's reference
    // renderer may use the lens model; the effects never use the lab).
    for effect in ["dof", "motion"] {
        assert!(
            !graph[effect].contains("lab"),
            "{effect}: {:?}",
            graph[effect]
        );
        assert!(
            !graph[effect].contains("process"),
            "{effect}: {:?}",
            graph[effect]
        );
    }
}

#[test]
fn no_modules_import_each_other_in_a_circle() {
    let graph = imports();
    // Depth-first search for a back edge, reporting the circle.
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) {
        if let Some(at) = path.iter().position(|n| n == node) {
            panic!(
                "modules import each other: {} -> {node}",
                path[at..].join(" -> ")
            );
        }
        if done.contains(node) {
            return;
        }
        path.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            visit(next, graph, path, done);
        }
        path.pop();
        done.insert(node.to_string());
    }
    let mut done = BTreeSet::new();
    for node in graph.keys() {
        visit(node, &graph, &mut Vec::new(), &mut done);
    }
    // The test sees the modules it guards.
    for module in [
        "cli", "dof", "io", "lab", "motion", "numeric", "process", "settings",
    ] {
        assert!(graph.contains_key(module), "{module} not found");
    }
}
