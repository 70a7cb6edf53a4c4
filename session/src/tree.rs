//! `ubf tree`: a scenario's behaviour tree as a picture, in Graphviz DOT or
//! Mermaid: each composite with its arbiter (and vote override), each child
//! with its share of the vote.

use ubf_core::Behavior;

/// A node of the tree, flattened in pre-order.
struct Node {
    label: String,
    parent: Option<(usize, f64)>,
    composite: bool,
}

fn flatten(behavior: &dyn Behavior, name: &str, parent: Option<(usize, f64)>, nodes: &mut Vec<Node>) {
    let index = nodes.len();
    let Some(composite) = behavior.as_composite() else {
        nodes.push(Node { label: name.to_owned(), parent, composite: false });
        return;
    };
    let vote = composite.vote_override().map(|v| format!("\\nvote {v}")).unwrap_or_default();
    nodes.push(Node { label: format!("{name}\\n{}{vote}", composite.arbiter_name()), parent, composite: true });
    let weights: Vec<f64> = composite.last_bids().iter().map(|b| b.weight).collect();
    for (i, (child_name, child)) in composite.children().enumerate() {
        flatten(child, child_name, Some((index, weights.get(i).copied().unwrap_or(0.0))), nodes);
    }
}

fn nodes(root: &dyn Behavior) -> Vec<Node> {
    let mut nodes = Vec::new();
    flatten(root, root.name(), None, &mut nodes);
    nodes
}

/// The tree as a Graphviz digraph: composites as boxes, behaviours as
/// rounded boxes, each edge labelled with the child's normalised weight.
pub fn dot(root: &dyn Behavior) -> String {
    let mut out = String::from("digraph tree {\n  node [fontname=\"sans-serif\"];\n");
    for (i, node) in nodes(root).iter().enumerate() {
        let shape = if node.composite { "box" } else { "box, style=rounded" };
        out.push_str(&format!("  n{i} [label=\"{}\", shape={shape}];\n", node.label.replace('"', "'")));
        if let Some((parent, weight)) = node.parent {
            out.push_str(&format!("  n{parent} -> n{i} [label=\"{weight:.2}\"];\n"));
        }
    }
    out.push_str("}\n");
    out
}

/// The tree as a Mermaid flowchart, for Markdown pages.
pub fn mermaid(root: &dyn Behavior) -> String {
    let mut out = String::from("flowchart TD\n");
    for (i, node) in nodes(root).iter().enumerate() {
        let label = node.label.replace("\\n", "<br/>").replace('"', "'");
        let (open, close) = if node.composite { ("[\"", "\"]") } else { ("(\"", "\")") };
        out.push_str(&format!("  n{i}{open}{label}{close}\n"));
        if let Some((parent, weight)) = node.parent {
            out.push_str(&format!("  n{parent} -- \"{weight:.2}\" --> n{i}\n"));
        }
    }
    out
}
