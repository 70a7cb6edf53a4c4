//! Behaviour trees from RON, by name.
//!
//! A [`Registry`] maps the name written in a file (`GoTo(cruise_speed: 0.5)`)
//! to a typed config and a constructor. Reading a file yields
//! [`BehaviorSpec`]s: checked, typed, not yet built. Building a spec with a
//! [`BuildContext`] (which carries the run's seed) gives the behaviour, so a
//! sweep reads a file once and builds it once per seed.

use crate::arbiter::ArbiterSpec;
use crate::config::{self, RonError};
use crate::describe::{Describe, Field};
use crate::{Behavior, Composite};
use rand_chacha::ChaCha8Rng;
use serde::de::{self, DeserializeOwned, Deserializer, EnumAccess, VariantAccess, Visitor};
use serde::Deserialize;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

type Factory = dyn Fn(&BuildContext) -> Box<dyn Behavior> + Send + Sync;
type Parser = dyn Fn(&mut dyn erased_serde::Deserializer) -> Result<Arc<Factory>, erased_serde::Error> + Send + Sync;

/// What a behaviour's constructor may know: the run's seed and where in the
/// tree it sits.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BuildContext {
    seed: u64,
    path: String,
}

impl BuildContext {
    /// The context of the root of a run with this seed.
    pub fn new(seed: u64) -> Self {
        BuildContext { seed, path: "root".to_owned() }
    }

    /// The run's seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Slash-separated child names from the root.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The context of the child `name` below this node.
    pub fn child(&self, name: &str) -> BuildContext {
        BuildContext { seed: self.seed, path: format!("{}/{}", self.path, name) }
    }

    /// A generator for this node: seeded by the run's seed, on a stream of
    /// its own chosen by the node's path, so that adding a behaviour elsewhere
    /// in the tree does not change this one's draws.
    pub fn rng(&self) -> ChaCha8Rng {
        crate::seeds::rng(self.seed, crate::seeds::Stream::Behavior(&self.path))
    }
}

/// A behaviour read from a file: its kind and its checked config, ready to
/// build.
#[derive(Clone)]
pub struct BehaviorSpec {
    kind: String,
    factory: Arc<Factory>,
}

impl BehaviorSpec {
    /// The registered name it was written as.
    pub fn kind(&self) -> &str {
        &self.kind
    }

    /// Builds the behaviour.
    pub fn build(&self, ctx: &BuildContext) -> Box<dyn Behavior> {
        (self.factory)(ctx)
    }
}

impl fmt::Debug for BehaviorSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("BehaviorSpec").field("kind", &self.kind).finish_non_exhaustive()
    }
}

/// Maps behaviour names to their configs and constructors.
///
/// `Composite` is always registered. Registering a name again replaces the
/// earlier entry, so a user's crate may override a stock behaviour.
#[derive(Clone)]
pub struct Registry {
    entries: BTreeMap<String, Entry>,
}

/// A registered behaviour: how to read its config, and what its fields are.
#[derive(Clone)]
struct Entry {
    parser: Arc<Parser>,
    fields: Arc<Vec<Field>>,
}

impl Default for Registry {
    fn default() -> Self {
        Self::new()
    }
}

impl Registry {
    /// A registry that knows only `Composite`.
    pub fn new() -> Self {
        let mut registry = Registry { entries: BTreeMap::new() };
        let composite = Entry { parser: Arc::new(parse_composite), fields: Arc::new(composite_fields()) };
        registry.entries.insert("Composite".to_owned(), composite);
        registry
    }

    /// Registers a behaviour under `name`: its config type `C` (use
    /// `#[serde(deny_unknown_fields)]` and the checkers of
    /// [`crate::config`]; its [`Describe`] says what the fields are) and a
    /// constructor from the config.
    pub fn register<C, B, F>(&mut self, name: &str, build: F) -> &mut Self
    where
        C: DeserializeOwned + Describe + Send + Sync + 'static,
        B: Behavior + 'static,
        F: Fn(&C, &BuildContext) -> B + Send + Sync + 'static,
    {
        let build = Arc::new(build);
        let parser = move |d: &mut dyn erased_serde::Deserializer| {
            let config: C = erased_serde::deserialize(d)?;
            let build = Arc::clone(&build);
            let factory: Arc<Factory> =
                Arc::new(move |ctx: &BuildContext| Box::new(build(&config, ctx)) as Box<dyn Behavior>);
            Ok(factory)
        };
        self.entries.insert(name.to_owned(), Entry { parser: Arc::new(parser), fields: Arc::new(C::fields()) });
        self
    }

    /// The fields of the behaviour registered as `name`, as its config
    /// describes them.
    pub fn fields(&self, name: &str) -> Option<&[Field]> {
        self.entries.get(name).map(|e| e.fields.as_slice())
    }

    /// The registered names, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.entries.keys().map(String::as_str)
    }

    /// Whether `name` is registered.
    pub fn contains(&self, name: &str) -> bool {
        self.entries.contains_key(name)
    }

    /// Reads a document that contains behaviour trees (fields of type
    /// [`BehaviorSpec`]) from RON text, with this registry resolving names.
    pub fn from_ron<T: DeserializeOwned>(&self, text: &str) -> Result<T, RonError> {
        let _active = ActiveRegistry::install(self.clone());
        config::from_ron(text)
    }
}

thread_local! {
    /// The registry resolving behaviour names while a document is read.
    /// serde has no way to hand context to a derived `Deserialize`, and
    /// behaviour specs sit deep inside user-defined documents.
    static ACTIVE: RefCell<Option<Registry>> = const { RefCell::new(None) };
}

struct ActiveRegistry(Option<Registry>);

impl ActiveRegistry {
    fn install(registry: Registry) -> Self {
        ActiveRegistry(ACTIVE.with(|a| a.replace(Some(registry))))
    }
}

impl Drop for ActiveRegistry {
    fn drop(&mut self) {
        ACTIVE.with(|a| *a.borrow_mut() = self.0.take());
    }
}

impl<'de> Deserialize<'de> for BehaviorSpec {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_enum("Behavior", &[], SpecVisitor)
    }
}

struct SpecVisitor;

impl<'de> Visitor<'de> for SpecVisitor {
    type Value = BehaviorSpec;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a behaviour, written `Name(config fields)`")
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<BehaviorSpec, A::Error> {
        let (Identifier(kind), variant) = data.variant::<Identifier>()?;
        let parser = ACTIVE.with(|active| match active.borrow().as_ref() {
            None => Err(de::Error::custom("behaviour trees must be read through Registry::from_ron")),
            Some(registry) => registry.entries.get(&kind).map(|e| Arc::clone(&e.parser)).ok_or_else(|| {
                let known: Vec<&str> = registry.names().collect();
                let meant = config::nearest(&kind, known.iter().copied())
                    .map_or(String::new(), |name| format!(" (did you mean `{name}`?)"));
                de::Error::custom(format!("unknown behaviour `{kind}`{meant}; known behaviours: {}", known.join(", ")))
            }),
        })?;
        let factory = variant.newtype_variant_seed(ConfigSeed(parser.as_ref()))?;
        Ok(BehaviorSpec { kind, factory })
    }
}

struct ConfigSeed<'a>(&'a Parser);

impl<'de> de::DeserializeSeed<'de> for ConfigSeed<'_> {
    type Value = Arc<Factory>;
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<Arc<Factory>, D::Error> {
        let mut erased = <dyn erased_serde::Deserializer>::erase(deserializer);
        (self.0)(&mut erased).map_err(de::Error::custom)
    }
}

struct Identifier(String);

impl<'de> Deserialize<'de> for Identifier {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct IdentVisitor;
        impl Visitor<'_> for IdentVisitor {
            type Value = Identifier;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a behaviour name")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Identifier, E> {
                Ok(Identifier(v.to_owned()))
            }
        }
        deserializer.deserialize_identifier(IdentVisitor)
    }
}

/// One child of a composite in a file:
/// `(behavior: GoTo(..), weight: 2.0, name: "go")`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ChildSpec {
    behavior: BehaviorSpec,
    #[serde(default = "unit_weight", deserialize_with = "config::non_negative")]
    weight: f64,
    #[serde(default)]
    name: Option<String>,
}

fn unit_weight() -> f64 {
    1.0
}

/// `Composite(name: .., arbiter: .., vote: .., children: [..])`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CompositeConfig {
    #[serde(default)]
    name: Option<String>,
    arbiter: ArbiterSpec,
    #[serde(default, deserialize_with = "config::optional_non_negative")]
    vote: Option<f64>,
    children: Vec<ChildSpec>,
}

/// `Composite`'s fields, as [`Describe`] gives a registered behaviour's.
fn composite_fields() -> Vec<Field> {
    vec![
        Field::new(
            "name",
            "text",
            "",
            "\"root\"",
            "",
            "the node's name (for the root; children are named by their entry)",
        ),
        Field::new("arbiter", "arbiter", "", "required", "", "how children combine: see [arbiters](arbiters.md)"),
        Field::new(
            "vote",
            "number",
            "",
            "None",
            "≥ 0",
            "a vote this composite bids to its parent in place of the one its arbiter gives",
        ),
        Field::new(
            "children",
            "list",
            "",
            "required",
            "",
            "`[(behavior: .., weight: .., name: ..), ..]`: each child, its weight (≥ 0, normalised over the children; 1 by default) and its name in records (the behaviour's by default; repeats get `_2`, `_3`…)",
        ),
    ]
}

fn parse_composite(d: &mut dyn erased_serde::Deserializer) -> Result<Arc<Factory>, erased_serde::Error> {
    use serde::de::Error as _;
    let config: CompositeConfig = erased_serde::deserialize(d)?;
    config.arbiter.check(config.children.len()).map_err(erased_serde::Error::custom)?;
    let names = unique_names(&config.children);
    let factory: Arc<Factory> = Arc::new(move |ctx: &BuildContext| {
        let name = config.name.clone().unwrap_or_else(|| "root".to_owned());
        let mut composite = Composite::with_arbiter(name, config.arbiter.build(ctx.child("arbiter").rng()));
        for (child, name) in config.children.iter().zip(&names) {
            composite.push_child(name.clone(), child.behavior.build(&ctx.child(name)), child.weight);
        }
        composite.set_vote(config.vote);
        Box::new(composite) as Box<dyn Behavior>
    });
    Ok(factory)
}

/// Child names default to the behaviour's kind; repeats get `_2`, `_3`… so
/// that every column of a trajectory file is unambiguous.
/// Linear in the number of children: a set of the names taken and, per
/// base name, the next suffix to try.
fn unique_names(children: &[ChildSpec]) -> Vec<String> {
    let mut taken: std::collections::HashSet<String> = std::collections::HashSet::with_capacity(children.len());
    let mut next_suffix: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    let mut names: Vec<String> = Vec::with_capacity(children.len());
    for child in children {
        let base = child.name.clone().unwrap_or_else(|| child.behavior.kind().to_owned());
        let mut name = base.clone();
        if taken.contains(&name) {
            let n = next_suffix.entry(base.clone()).or_insert(2);
            loop {
                name = format!("{base}_{n}");
                *n += 1;
                if !taken.contains(&name) {
                    break;
                }
            }
        }
        taken.insert(name.clone());
        names.push(name);
    }
    names
}
