//! ARCHITECTURE.md stays true and short: every path it names in backticks exists, and it is a
//! page a newcomer reads in ten minutes (at most 12 KB; the detail lives in the module docs).
//! The layers of the library and of the CLI point one way (their module graphs have no cycle).

use std::path::Path;

#[test]
fn architecture_is_at_most_12_kb() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let size = std::fs::metadata(root.join("ARCHITECTURE.md")).unwrap().len();
    assert!(
        size <= 12 * 1024,
        "ARCHITECTURE.md is {size} bytes, more than 12 KB: move the detail into module docs"
    );
}

#[test]
fn architecture_paths_exist() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let mut checked = 0;
    for (i, piece) in text.split('`').enumerate() {
        // Odd pieces are inside backticks; paths are the ones with a slash and no spaces.
        if i % 2 == 1 && piece.contains('/') && !piece.contains(' ') && !piece.contains("::") {
            assert!(root.join(piece).exists(), "ARCHITECTURE.md names `{piece}`, which does not exist");
            checked += 1;
        }
    }
    assert!(checked >= 10, "only {checked} paths found");
}

type Graph = std::collections::BTreeMap<String, std::collections::BTreeSet<String>>;

/// The library's top-level modules (`crates/pendula/src/NAME.rs` or `NAME/`) and, for each,
/// the top-level modules its code names.
fn module_graph() -> Graph {
    module_graph_of(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), 1)
}

/// The CLI's modules and, for each, the modules its code names: its top-level modules and
/// each command (`commands::sweep`), with `crate`, the root (`lib.rs`: dispatch), on top.
fn cli_module_graph() -> Graph {
    module_graph_of(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../pendula-cli/src"), 2)
}

/// The modules of the crate whose sources are in `src`, each file's module cut to its first
/// `depth` names (`system::double` is `system` at depth 1), and for each the modules its code
/// names: `crate::` paths, with groups nested to any depth (`crate::{a::{b, c}, d}`),
/// `super::` paths and paths through its own submodules (the root's `commands::sweep::run`); a
/// path to an item resolves to the module that holds it, a name the crate
/// root re-exports to the module it comes from (lib.rs's `pub use` lines), an item of the root
/// itself to `crate`; a macro (`macro_rules!` at a module's top level) used by name in
/// another module is an import of the module that defines it. Comments, where links are not
/// imports, and `#[cfg(test)]` modules, whose tests may call on anything, are skipped.
fn module_graph_of(src: &Path, depth: usize) -> Graph {
    use std::collections::{BTreeMap, BTreeSet};
    // What the crate root re-exports, and from where (lib.rs's `pub use` lines).
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let mut reexport: BTreeMap<String, String> = BTreeMap::new();
    for line in lib.lines().filter(|l| l.starts_with("pub use ")) {
        let path = line.trim_start_matches("pub use ").trim_end_matches(';');
        let module = path.split("::").next().unwrap().to_owned();
        let names = path.rsplit("::").next().unwrap();
        let last = path.split("::").filter(|p| !p.starts_with('{')).last().unwrap();
        for name in names.trim_matches(|c| c == '{' || c == '}').split(',').map(str::trim).chain([last]) {
            reexport.insert(name.to_owned(), module.clone());
        }
    }
    // Every file: its module's path (`commands::sweep`; the root's is empty) and its code.
    let mut sources: Vec<(Vec<String>, String)> = Vec::new();
    let mut files = vec![src.to_path_buf()];
    while let Some(path) = files.pop() {
        if path.is_dir() {
            files.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
            continue;
        }
        if path.extension().is_none_or(|e| e != "rs") || path == src.join("main.rs") {
            continue;
        }
        let relative = path.strip_prefix(src).unwrap().with_extension("");
        let mut module: Vec<String> =
            relative.components().map(|c| c.as_os_str().to_str().unwrap().to_owned()).collect();
        if module.last().is_some_and(|m| m == "mod" || m == "lib") {
            module.pop();
        }
        sources.push((module, without_tests(&std::fs::read_to_string(&path).unwrap())));
    }
    let modules: BTreeSet<Vec<String>> = sources.iter().map(|(m, _)| m.clone()).collect();
    // A module's node: its path cut to `depth` names; the root is `crate`.
    let node = |module: &[String]| -> String {
        if module.is_empty() { "crate".to_owned() } else { module[..module.len().min(depth)].join("::") }
    };
    // The module that holds the item at `path` (names from the crate root).
    let holder = |path: &[String]| -> String {
        let mut path = path.to_vec();
        if let Some(module) = path.first().and_then(|first| reexport.get(first)) {
            path[0] = module.clone();
        }
        let known = (0..=path.len()).rev().find(|&k| modules.contains(&path[..k])).unwrap_or(0);
        node(&path[..known])
    };
    let mut macros: BTreeMap<String, String> = BTreeMap::new();
    for (module, code) in &sources {
        for line in code.lines().filter(|l| l.starts_with("macro_rules! ")) {
            let name =
                line["macro_rules! ".len()..].split(|c: char| !(c.is_alphanumeric() || c == '_')).next();
            macros.insert(name.unwrap().to_owned(), node(module));
        }
    }
    let mut graph: Graph = BTreeMap::new();
    for (module, code) in &sources {
        let here = node(module);
        let uses = graph.entry(here.clone()).or_default();
        let children: Vec<String> = modules
            .iter()
            .filter(|m| m.len() == module.len() + 1 && m.starts_with(module))
            .map(|m| m[module.len()].clone())
            .collect();
        for path in imports(code, module, &children) {
            let target = holder(&path);
            if target != here {
                uses.insert(target);
            }
        }
        for (name, defined) in &macros {
            if *defined != here && code.contains(&format!("{name}!")) {
                uses.insert(defined.clone());
            }
        }
    }
    graph
}

/// `code` without its comment lines and its `#[cfg(test)]` modules.
fn without_tests(code: &str) -> String {
    let mut code: String =
        code.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n");
    while let Some(at) = code.find("#[cfg(test)]\nmod ") {
        let open = at + code[at..].find('{').unwrap();
        // The module's closing brace: braces counted outside string literals.
        let (mut depth, mut in_string, mut escaped, mut end) = (0, false, false, code.len());
        for (i, c) in code[open..].char_indices() {
            match c {
                _ if escaped => escaped = false,
                '\\' if in_string => escaped = true,
                '"' => in_string = !in_string,
                '{' if !in_string => depth += 1,
                '}' if !in_string => {
                    depth -= 1;
                    if depth == 0 {
                        end = open + i + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        code.replace_range(at..end, "");
    }
    code
}

/// The paths, from the crate root, that `code` (of the module at `module`, whose submodules
/// are `children`) names with `crate::`, `super::` or a submodule's name, groups expanded:
/// `crate::{a::{b, c}, d}` names `a::b`, `a::c` and `d`; `super::x` in `a::b` names `a::x`;
/// `b::x` in `a`, when `b` is a child, names `a::b::x`.
fn imports(code: &str, module: &[String], children: &[String]) -> Vec<Vec<String>> {
    let mut found = Vec::new();
    for child in children {
        for (i, _) in code.match_indices(&format!("{child}::")) {
            let before = code[..i].chars().next_back();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            expand(&code[i..], module.to_vec(), &mut found);
        }
    }
    for (prefix, base) in [("crate::", &module[..0]), ("super::", &module[..module.len().saturating_sub(1)])]
    {
        for (i, _) in code.match_indices(prefix) {
            let before = code[..i].chars().next_back();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            expand(&code[i + prefix.len()..], base.to_vec(), &mut found);
        }
    }
    found
}

/// Adds to `found` the paths that `rest` (the text after `crate::` or after a group's `::`)
/// names under `prefix`: one path, or a `{…}` group's, each of its items expanded in turn.
fn expand(rest: &str, prefix: Vec<String>, found: &mut Vec<Vec<String>>) {
    if let Some(group) = rest.strip_prefix('{') {
        // The group's items: split at its top-level commas, up to its closing brace.
        let (mut depth, mut start) = (0, 0);
        for (i, c) in group.char_indices() {
            match c {
                '{' => depth += 1,
                '}' if depth == 0 => {
                    expand_item(&group[start..i], &prefix, found);
                    return;
                }
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand_item(&group[start..i], &prefix, found);
                    start = i + 1;
                }
                _ => {}
            }
        }
        return;
    }
    let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
    if name.is_empty() {
        return;
    }
    let mut path = prefix;
    path.push(name.clone());
    match rest[name.len()..].strip_prefix("::") {
        Some(more) if more.starts_with(|c: char| c == '{' || c.is_alphabetic() || c == '_') => {
            expand(more, path, found)
        }
        _ => found.push(path),
    }
}

/// One item of a group: `self` (the group's own module), or a path expanded under `prefix`.
fn expand_item(item: &str, prefix: &[String], found: &mut Vec<Vec<String>>) {
    let item = item.trim();
    if item == "self" || item.starts_with("self ") {
        found.push(prefix.to_vec());
    } else if !item.is_empty() {
        expand(item, prefix.to_vec(), found);
    }
}

/// A cycle of `graph`, if it has one (depth-first search for a back edge).
fn cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        graph: &Graph,
        node: &str,
        path: &mut Vec<String>,
        done: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        if done.iter().any(|d| d == node) {
            return None;
        }
        if let Some(i) = path.iter().position(|n| n == node) {
            return Some([&path[i..], &[node.to_owned()]].concat());
        }
        path.push(node.to_owned());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(found) = visit(graph, next, path, done) {
                return Some(found);
            }
        }
        path.pop();
        done.push(node.to_owned());
        None
    }
    let mut done = Vec::new();
    graph.keys().find_map(|node| visit(graph, node, &mut Vec::new(), &mut done))
}

/// Layers point one way: the top-level modules' graph has no cycle, and `system` (the
/// equations) imports nothing but the number types, special functions and errors — none of
/// the integrators, the run loop, the observers, the controllers or the ensemble engine built
/// on it (issue 13).
#[test]
fn the_module_graph_has_no_cycle_and_systems_are_at_the_bottom() {
    let graph = module_graph();
    assert!(graph.len() >= 10, "found only {:?}", graph.keys());
    for layer in ["simulate", "integrator", "ensemble", "model", "system", "num"] {
        assert!(graph.contains_key(layer), "no module {layer} in {:?}", graph.keys());
    }
    let system = &graph["system"];
    assert!(
        system.iter().all(|m| ["error", "num", "special"].contains(&m.as_str())),
        "system imports {system:?}"
    );
    assert!(graph["simulate"].contains("system"), "the scan finds imports: {graph:?}");
    assert_eq!(cycle(&graph), None, "the modules' graph: {graph:?}");
}

/// The cycle check can fail: the real graph with one edge planted upwards has a cycle.
#[test]
fn a_planted_cycle_is_found() {
    let mut graph = module_graph();
    graph.get_mut("system").unwrap().insert("simulate".into());
    let found = cycle(&graph).expect("a cycle");
    assert_eq!(found.first(), found.last());
    assert!(found.contains(&"system".to_owned()) && found.contains(&"simulate".to_owned()), "{found:?}");
}

/// The CLI's layers point one way: value and argument parsing at the bottom, the helpers the
/// commands share, the commands, the command line (`cli`) and the dispatch (`crate`) on top —
/// no module imports one that imports it back, commands included (issue 30).
#[test]
fn the_cli_module_graph_has_no_cycle() {
    let graph = cli_module_graph();
    // A scan that finds the modules (29 when convergence and work-precision moved to the registry).
    assert!(graph.len() >= 25, "found only {:?}", graph.keys());
    for module in ["crate", "cli", "parse", "config", "study", "output", "commands::sweep", "commands::merge"]
    {
        assert!(graph.contains_key(module), "no module {module} in {:?}", graph.keys());
    }
    // The scan finds imports: grouped, nested, through `super::`, and macros.
    assert!(graph["cli"].contains("commands::report"), "the list of commands: {graph:?}");
    assert!(graph["commands::compare"].contains("study"), "{graph:?}");
    assert!(graph["studies"].contains("study"), "the registry's commands: {graph:?}");
    assert!(graph["parse"].is_empty(), "parsing is the bottom layer: it imports {:?}", graph["parse"]);
    assert_eq!(cycle(&graph), None, "the CLI's modules' graph: {graph:?}");
}

/// The scan reads nested groups: `crate::{a::{b, c}, d}` names `a::b`, `a::c` and `d`, and
/// one planted in the CLI's parsing layer closes a cycle that the check finds.
#[test]
fn a_planted_nested_group_import_is_found() {
    let here = ["parse".to_owned()];
    let planted = "use crate::{args::{self, LargeArg}, commands::{sweep::{SweepArgs, DEFAULTS}, merge}};";
    let paths: Vec<String> = imports(planted, &here, &[]).iter().map(|p| p.join("::")).collect();
    assert_eq!(
        paths,
        [
            "args",
            "args::LargeArg",
            "commands::sweep::SweepArgs",
            "commands::sweep::DEFAULTS",
            "commands::merge"
        ]
    );
    let inner = ["commands".to_owned(), "fractal".to_owned()];
    let paths: Vec<String> =
        imports("super::{sweep::parse_axis, merge};", &inner, &[]).iter().map(|p| p.join("::")).collect();
    assert_eq!(paths, ["commands::sweep::parse_axis", "commands::merge"]);
    let mut graph = cli_module_graph();
    graph.get_mut("parse").unwrap().extend(["commands::sweep".to_owned()]);
    let found = cycle(&graph).expect("a cycle");
    assert_eq!(found.first(), found.last());
    assert!(
        found.contains(&"parse".to_owned()) && found.contains(&"commands::sweep".to_owned()),
        "{found:?}"
    );
}
