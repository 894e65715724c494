//! ARCHITECTURE.md stays true and short: every path it names in backticks exists, and it is a
//! page a newcomer reads in ten minutes (at most 12 KB; the detail lives in the module docs).

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

/// The library's top-level modules (`crates/pendula/src/NAME.rs` or `NAME/`) and, for each,
/// the top-level modules its code names (`crate::NAME`, `crate::{A, B}`, the crate root's
/// re-exports resolved to their modules; comments, where links are not imports, skipped).
fn module_graph() -> std::collections::BTreeMap<String, std::collections::BTreeSet<String>> {
    use std::collections::{BTreeMap, BTreeSet};
    // What the crate root re-exports, and from where (lib.rs's `pub use` lines).
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
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
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut files = vec![src.clone()];
    while let Some(path) = files.pop() {
        if path.is_dir() {
            files.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
            continue;
        }
        if path.extension().is_none_or(|e| e != "rs") || path == src.join("lib.rs") {
            continue;
        }
        let relative = path.strip_prefix(&src).unwrap();
        let top = relative.components().next().unwrap().as_os_str().to_str().unwrap();
        let top = top.trim_end_matches(".rs").to_owned();
        let code: String = std::fs::read_to_string(&path)
            .unwrap()
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        let uses = graph.entry(top.clone()).or_default();
        for (i, _) in code.match_indices("crate::") {
            let rest = &code[i + "crate::".len()..];
            let names: Vec<&str> = if let Some(group) = rest.strip_prefix('{') {
                group[..group.find('}').unwrap()]
                    .split(',')
                    .map(|n| n.trim().split("::").next().unwrap())
                    .collect()
            } else {
                vec![rest.split(|c: char| !(c.is_alphanumeric() || c == '_')).next().unwrap()]
            };
            for name in names.into_iter().filter(|n| !n.is_empty()) {
                let module = reexport.get(name).cloned().unwrap_or_else(|| name.to_owned());
                if module != top {
                    uses.insert(module);
                }
            }
        }
    }
    graph
}

type Graph = std::collections::BTreeMap<String, std::collections::BTreeSet<String>>;

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
