//! The shape of the code: no two top-level modules import each other, directly or in a
//! circle, so each can be read (and given its GPU twin) without the ones above it; `dof` and
//! `motion` are siblings that never import each other. Test-only code (after `#[cfg(test)]`)
//! is left out, as dev-dependencies are.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The top-level module each source file of `src/` belongs to, and the top-level modules its
/// non-test code names through `crate::`.
fn imports() -> BTreeMap<String, BTreeSet<String>> {
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in source_files() {
        let module = file
            .iter()
            .next()
            .unwrap()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string();
        if ["lib", "main"].contains(&module.as_str()) {
            continue;
        }
        let code = code_of(&file);
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
    graph
}

/// The code of a file under `src/`: comments (which may name any module) and test-only code
/// (after `#[cfg(test)]`, as dev-dependencies are) left out.
fn code_of(file: &Path) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("src").join(file);
    std::fs::read_to_string(path)
        .unwrap()
        .split("#[cfg(test)]")
        .next()
        .unwrap()
        .lines()
        .map(|l| l.split("//").next().unwrap())
        .collect::<Vec<_>>()
        .join("\n")
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

/// Every Rust source file under `src/`, by its path relative to `src/`.
fn source_files() -> Vec<PathBuf> {
    files_under_src(&["rs"])
}

/// Every file under `src/` whose extension is one of `extensions`, relative to `src/`.
fn files_under_src(extensions: &[&str]) -> Vec<PathBuf> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    let mut stack = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path
                .extension()
                .is_some_and(|e| extensions.iter().any(|x| e == *x))
            {
                files.push(path.strip_prefix(&src).unwrap().to_path_buf());
            }
        }
    }
    files.sort();
    files
}

/// The module path of a file: `motion/reconstruct/matte.rs` → [motion, reconstruct, matte];
/// a `mod.rs` is its folder's module; `lib.rs` and `main.rs` the crate root.
fn module_of(file: &Path) -> Vec<String> {
    let mut parts: Vec<String> = file
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// The file that defines the longest prefix of `path` (a module path from the crate root)
/// that is a file: the file an item path reaches into.
fn file_of(path: &[String], files: &BTreeSet<PathBuf>) -> Option<PathBuf> {
    let mut found = None;
    for n in 0..=path.len() {
        let prefix = path[..n].join("/");
        let candidates = if n == 0 {
            vec![PathBuf::from("lib.rs")]
        } else {
            vec![
                PathBuf::from(format!("{prefix}.rs")),
                PathBuf::from(format!("{prefix}/mod.rs")),
            ]
        };
        match candidates.into_iter().find(|c| files.contains(c)) {
            Some(file) => found = Some(file),
            None => break,
        }
    }
    found
}

/// The paths a file's `use` declarations name, braces expanded (`a::{b, c::d}` → `a::b`,
/// `a::c::d`; `self` in braces is the prefix itself).
fn use_paths(code: &str) -> Vec<String> {
    fn expand(tree: &str, prefix: &str, out: &mut Vec<String>) {
        let tree = tree.trim();
        if let Some(open) = tree.find('{') {
            let head = tree[..open].trim().trim_end_matches("::");
            let body = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
            let prefix = join(prefix, head);
            // Split the body at top-level commas.
            let (mut depth, mut start) = (0, 0);
            let bytes: Vec<char> = body.chars().collect();
            let mut pieces = Vec::new();
            for (i, c) in bytes.iter().enumerate() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        pieces.push(bytes[start..i].iter().collect::<String>());
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            pieces.push(bytes[start..].iter().collect::<String>());
            for piece in pieces {
                expand(&piece, &prefix, out);
            }
        } else {
            let path = tree.split(" as ").next().unwrap().trim();
            if path.is_empty() {
                return;
            }
            if path == "self" {
                out.push(prefix.to_string());
            } else {
                out.push(join(prefix, path));
            }
        }
    }
    fn join(a: &str, b: &str) -> String {
        match (a.is_empty(), b.is_empty()) {
            (true, _) => b.to_string(),
            (_, true) => a.to_string(),
            _ => format!("{a}::{b}"),
        }
    }
    let mut out = Vec::new();
    for statement in code.split(';') {
        let statement = statement.trim();
        let Some(at) = statement.find("use ") else {
            continue;
        };
        let before = &statement[..at];
        // `pub use`, `pub(crate) use`: a re-export publishes an item where callers find it
        // (a folder's `mod.rs` as its front door); it is not an import of the file's own
        // code, so it is left out (callers then name the file that defines what they use).
        if before.trim_end().ends_with("pub") || before.trim_end().ends_with(')') {
            continue;
        }
        if !(before.is_empty() || before.ends_with('\n') || before.trim_end().ends_with(']')) {
            continue;
        }
        expand(&statement[at + 4..], "", &mut out);
    }
    out
}

/// The files each file of `src/` imports: through `use` declarations and through paths in
/// its code that start with `crate::` or `super::`, each resolved to the file that defines
/// the longest module prefix it names (an item named through a parent's re-export counts as
/// the parent's). Re-exports themselves (`pub use`) and test-only code are left out.
fn file_imports() -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let files: BTreeSet<PathBuf> = source_files().into_iter().collect();
    let mut graph = BTreeMap::new();
    for file in &files {
        let code = code_of(file);
        let module = module_of(file);
        let mut paths = use_paths(&code);
        for start in ["crate::", "super::"] {
            for (i, _) in code.match_indices(start) {
                if i > 0 {
                    let before = code[..i].chars().next_back().unwrap();
                    if before.is_ascii_alphanumeric() || before == '_' || before == ':' {
                        continue;
                    }
                }
                let path: String = code[i..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':')
                    .collect();
                // `crate::a::{b, c}`: a use group, which `use_paths` expands (a `pub use`
                // group is a re-export and left out there).
                if !path.ends_with("::") {
                    paths.push(path);
                }
            }
        }
        let mut uses = BTreeSet::new();
        for path in paths {
            let parts: Vec<&str> = path.split("::").filter(|p| !p.is_empty()).collect();
            let absolute: Vec<String> = match parts.first() {
                Some(&"crate") => parts[1..].iter().map(|s| s.to_string()).collect(),
                Some(&"super") => {
                    let mut base = module.clone();
                    let mut rest = &parts[..];
                    while rest.first() == Some(&"super") {
                        base.pop();
                        rest = &rest[1..];
                    }
                    base.extend(rest.iter().map(|s| s.to_string()));
                    base
                }
                Some(&"self") => {
                    let mut base = module.clone();
                    base.extend(parts[1..].iter().map(|s| s.to_string()));
                    base
                }
                // A child module of this one (`use config::Form;` beside `mod config;`).
                Some(first) => {
                    let mut child = module.clone();
                    child.push(first.to_string());
                    if file_of(&child, &files).is_none_or(|f| module_of(&f) != child) {
                        continue;
                    }
                    child.extend(parts[1..].iter().map(|s| s.to_string()));
                    child
                }
                None => continue,
            };
            if let Some(target) = file_of(&absolute, &files) {
                if &target != file {
                    uses.insert(target);
                }
            }
        }
        graph.insert(file.clone(), uses);
    }
    graph
}

#[test]
fn no_files_import_each_other_in_a_circle() {
    let graph = file_imports();
    fn visit(
        node: &PathBuf,
        graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>,
        path: &mut Vec<PathBuf>,
        done: &mut BTreeSet<PathBuf>,
        found: &mut Vec<String>,
    ) {
        if let Some(at) = path.iter().position(|n| n == node) {
            let circle: Vec<String> = path[at..]
                .iter()
                .chain([node])
                .map(|p| p.display().to_string())
                .collect();
            found.push(circle.join(" -> "));
            return;
        }
        if done.contains(node) {
            return;
        }
        path.push(node.clone());
        for next in graph.get(node).into_iter().flatten() {
            visit(next, graph, path, done, found);
        }
        path.pop();
        done.insert(node.clone());
    }
    let (mut done, mut found) = (BTreeSet::new(), Vec::new());
    for node in graph.keys() {
        visit(node, &graph, &mut Vec::new(), &mut done, &mut found);
    }
    assert!(
        found.is_empty(),
        "files import each other:\n{}",
        found.join("\n")
    );
    // The test sees the imports it guards.
    let matte = PathBuf::from("motion/reconstruct/matte.rs");
    assert!(
        graph[&matte].contains(&PathBuf::from("motion/reconstruct/config.rs")),
        "{:?}",
        graph[&matte]
    );
}
/// Past this many lines a file's seams hide: split it along them.
const MOST_LINES: usize = 800;

#[test]
fn no_source_file_is_over_800_lines() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let long: Vec<String> = files_under_src(&["rs", "wgsl"])
        .into_iter()
        .filter_map(|file| {
            let lines = std::fs::read_to_string(src.join(&file))
                .unwrap()
                .lines()
                .count();
            (lines > MOST_LINES).then(|| format!("{} ({lines} lines)", file.display()))
        })
        .collect();
    assert!(long.is_empty(), "over {MOST_LINES} lines: {long:?}");
}

/// A message's lines joined in the source with a lost `\` continuation hold the next
/// line's indentation: "draws each                  bokeh round" was printed so. No string
/// literal on one line of `src/` holds a run of twelve spaces or more after a word (tables
/// of `shutter info` align with fewer).
#[test]
fn no_message_holds_a_run_of_spaces_where_its_lines_were_joined() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut found = Vec::new();
    for file in source_files() {
        let code = std::fs::read_to_string(src.join(&file)).unwrap();
        for (n, line) in code.lines().enumerate() {
            if line.trim_start().starts_with("//") {
                continue;
            }
            // The parts of the line inside quotes (every other part, split at each `"`).
            let quoted = line.split('"').skip(1).step_by(2);
            let run = " ".repeat(12);
            let joined = quoted
                .into_iter()
                .any(|text| text.trim_start().contains(&run));
            if joined {
                found.push(format!("{}:{}", file.display(), n + 1));
            }
        }
    }
    assert!(
        found.is_empty(),
        "lines joined with their indentation: {found:?}"
    );
}

/// docs/ARCHITECTURE.md's "Every file" section: the files it names, each resolved against the
/// folder heading above it (a line that starts with `` `src/…/` ``).
fn files_the_architecture_names() -> BTreeSet<PathBuf> {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/ARCHITECTURE.md"))
            .unwrap();
    let section = doc
        .split("\n## Every file\n")
        .nth(1)
        .expect("docs/ARCHITECTURE.md has a section '## Every file'")
        .split("\n## ")
        .next()
        .unwrap();
    let mut folder = PathBuf::new();
    let mut named = BTreeSet::new();
    for line in section.lines() {
        let names: Vec<&str> = line.split('`').skip(1).step_by(2).collect();
        if let Some(heading) = line.strip_prefix('`').and_then(|l| l.split('`').next()) {
            if let Some(path) = heading.strip_prefix("src/").filter(|p| p.ends_with('/')) {
                folder = PathBuf::from(path);
            } else if heading == "src/" {
                folder = PathBuf::new();
            }
        }
        for name in names {
            if name.ends_with(".rs") || name.ends_with(".wgsl") {
                named.insert(folder.join(name));
            }
        }
    }
    named
}

#[test]
fn the_architecture_names_every_source_file_and_no_other() {
    let files: BTreeSet<PathBuf> = files_under_src(&["rs", "wgsl"]).into_iter().collect();
    let named = files_the_architecture_names();
    let missing: Vec<_> = files.difference(&named).collect();
    let stale: Vec<_> = named.difference(&files).collect();
    assert!(
        missing.is_empty() && stale.is_empty(),
        "docs/ARCHITECTURE.md ('Every file'): files it does not name {missing:?}; names of \
         files that do not exist {stale:?}"
    );
    // And the module table has a row for every top-level module.
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/ARCHITECTURE.md"))
            .unwrap();
    for module in imports().keys() {
        assert!(
            doc.contains(&format!("\n| `{module}` |")),
            "docs/ARCHITECTURE.md's module table has no row for {module}"
        );
    }
}
