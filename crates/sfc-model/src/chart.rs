//! The chart of one SFC POU: steps, transitions and actions with resolved references, and the
//! divergences and convergences the text implies.

use sfc_diagnostics::Span;
use sfc_syntax::ast;

/// Index of a step in [`Chart::steps`].
pub type StepId = usize;
/// Index of a transition in [`Chart::transitions`].
pub type TransitionId = usize;
/// Index of an action in [`Chart::actions`].
pub type ActionId = usize;

/// Which REX block (if any) the chart is meant for; it adds target rules to validation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Target {
    Blank,
    Atmt,
    Eatmt,
}

impl Target {
    /// Parses `blank`, `atmt`, `eatmt` (any case).
    pub fn from_name(s: &str) -> Option<Target> {
        match s.to_ascii_lowercase().as_str() {
            "blank" => Some(Target::Blank),
            "atmt" => Some(Target::Atmt),
            "eatmt" => Some(Target::Eatmt),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Target::Blank => "blank",
            Target::Atmt => "atmt",
            Target::Eatmt => "eatmt",
        }
    }
}

/// The eleven action qualifiers of IEC 61131-3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Qualifier {
    N,
    R,
    S,
    L,
    D,
    P,
    SD,
    DS,
    SL,
    P1,
    P0,
}

impl Qualifier {
    pub const ALL: [Qualifier; 11] = [
        Qualifier::N,
        Qualifier::R,
        Qualifier::S,
        Qualifier::L,
        Qualifier::D,
        Qualifier::P,
        Qualifier::SD,
        Qualifier::DS,
        Qualifier::SL,
        Qualifier::P1,
        Qualifier::P0,
    ];
    pub fn from_name(s: &str) -> Option<Qualifier> {
        Qualifier::ALL.iter().copied().find(|q| q.name().eq_ignore_ascii_case(s))
    }
    pub fn name(self) -> &'static str {
        match self {
            Qualifier::N => "N",
            Qualifier::R => "R",
            Qualifier::S => "S",
            Qualifier::L => "L",
            Qualifier::D => "D",
            Qualifier::P => "P",
            Qualifier::SD => "SD",
            Qualifier::DS => "DS",
            Qualifier::SL => "SL",
            Qualifier::P1 => "P1",
            Qualifier::P0 => "P0",
        }
    }
    /// L, D, SD, DS and SL take a duration.
    pub fn is_timed(self) -> bool {
        matches!(self, Qualifier::L | Qualifier::D | Qualifier::SD | Qualifier::DS | Qualifier::SL)
    }
}

/// The duration of a timed association.
#[derive(Debug, Clone, PartialEq)]
pub enum Duration {
    /// A literal, in microseconds.
    Literal(i64),
    /// A TIME variable, by declared name.
    Variable(String),
}

/// What an association drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ActionTarget {
    /// An ACTION of the POU.
    Action(ActionId),
    /// A BOOL variable used as an action (it takes the value of `Q`).
    Variable,
}

/// `Action(Q, T#1s, Indicator)` inside a step.
#[derive(Debug, Clone, PartialEq)]
pub struct Association {
    /// The action name as written.
    pub action: String,
    pub target: ActionTarget,
    pub qualifier: Qualifier,
    pub duration: Option<Duration>,
    pub indicators: Vec<String>,
    pub span: Span,
}

/// A step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepNode {
    pub name: String,
    pub initial: bool,
    pub associations: Vec<Association>,
    /// CODESYS's step actions (entry, step, exit), as written.
    pub step_actions: Vec<ast::StepAction>,
    /// `sfc.tag`: the ATMT/EATMT state number.
    pub tag: Option<u32>,
    /// `sfc.timeout`: supervision time in microseconds.
    pub timeout: Option<i64>,
    /// `sfc.min_time`: minimum time in microseconds (CODESYS's "minimum time" of a step): its
    /// outgoing transitions wait for it.
    pub min_time: Option<i64>,
    /// `sfc.final`: intentionally without a way out.
    pub is_final: bool,
    /// S7-GRAPH's interlock (`sfc.s7graph.interlock`): the step's interlock-dependent actions
    /// run only while it is TRUE.
    pub interlock: Option<ast::Expr>,
    /// S7-GRAPH's supervision (`sfc.s7graph.supervision`): TRUE is a supervision error.
    pub supervision: Option<ast::Expr>,
    pub attributes: Vec<ast::Attribute>,
    /// Span of the name.
    pub name_span: Span,
    pub span: Span,
}

/// A transition.
#[derive(Debug, Clone, PartialEq)]
pub struct TransitionNode {
    /// The declared name, or `T<n>` for an unnamed one (see `semantics.md`).
    pub name: String,
    pub named: bool,
    pub priority: Option<i64>,
    pub from: Vec<StepId>,
    pub to: Vec<StepId>,
    pub condition: ast::Condition,
    /// `sfc.tag`: the ATMT/EATMT condition index.
    pub tag: Option<u32>,
    pub attributes: Vec<ast::Attribute>,
    /// Span of the `TRANSITION … FROM … TO …` header (for diagnostics).
    pub header_span: Span,
    pub span: Span,
}

/// An action.
#[derive(Debug, Clone, PartialEq)]
pub struct ActionNode {
    pub name: String,
    pub body: ast::ActionBody,
    pub attributes: Vec<ast::Attribute>,
    pub name_span: Span,
    pub span: Span,
}

impl ActionNode {
    /// An action of an instance associated with a step (`Motor.Stop`): not declared in the POU,
    /// its body is the call of it.
    pub fn of_instance(&self) -> bool {
        self.name.contains('.')
    }
}

/// A branching structure implied by the connections.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Branch {
    /// A step with several outgoing transitions (OR divergence).
    SelectionDivergence { step: StepId, transitions: Vec<TransitionId> },
    /// A step with several incoming transitions (OR convergence).
    SelectionConvergence { step: StepId, transitions: Vec<TransitionId> },
    /// A transition with several following steps (AND divergence).
    SimultaneousDivergence { transition: TransitionId, steps: Vec<StepId> },
    /// A transition with several preceding steps (AND convergence).
    SimultaneousConvergence { transition: TransitionId, steps: Vec<StepId> },
}

/// Transitions leaving and entering each step, indexed by [`StepId`], in declaration order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Adjacency {
    pub outgoing: Vec<Vec<TransitionId>>,
    pub incoming: Vec<Vec<TransitionId>>,
}

/// Studio 5000's SFC execution settings, which are the controller's in Logix (its Controller
/// Properties, "SFC Execution" tab) and which the L5X import writes on each chart's POU
/// (`sfc.logix.exec`, `sfc.logix.lastscan`); the simulator's `logix` profile follows them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LogixSettings {
    /// "Execute until FALSE transition" (`UntilFalse`); the default is "Execute current active
    /// steps only" (`CurrentActive`).
    pub until_false: bool,
    /// "Last Scan of Active Steps".
    pub last_scan: LastScan,
}

/// The S7-GRAPH block settings the simulator's `graph` profile follows, kept by the SimaticML
/// import on the block's POU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GraphSettings {
    /// "Acknowledge errors" (`sfc.s7graph.ack_required`, TIA's `AcknowledgeErrorsRequired`,
    /// on by default): a supervision error holds its step until it is gone and acknowledged
    /// with `ACK_EF`; off, until it is gone.
    pub ack_required: bool,
}

impl Default for GraphSettings {
    fn default() -> Self {
        GraphSettings { ack_required: true }
    }
}

/// How the tool a chart was written for runs the two things a conversion to another vendor most
/// often changes, so that an export says what changes (and only that): from the POU's
/// `sfc.dialect` (none: IEC 61131-3) and, for Studio 5000, its last-scan setting. The rules are
/// the simulator's profiles' (docs/sim.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunRules {
    /// Who runs the chart so: "IEC 61131-3", "CODESYS", "Studio 5000", "S7-GRAPH".
    pub name: &'static str,
    /// An action that stops (its step left, its time over, reset) runs once more, with Q FALSE.
    pub final_run: bool,
    /// The first call already tests the initial steps' transitions.
    pub first_call_tests: bool,
    /// A call runs the actions of the active steps before it tests the transitions (CODESYS,
    /// Logix), so a step's actions start in the call after it is entered; otherwise (IEC,
    /// S7-GRAPH) the transitions fire first and the entered step's actions run in the same call.
    pub actions_first: bool,
}

impl RunRules {
    /// The note of a conversion from rules `from` to rules `to` whose call orders differ (what
    /// the chart's outputs do differently), `None` when they are the same.
    pub fn order_change(from: RunRules, to: RunRules) -> Option<String> {
        (from.actions_first != to.actions_first).then(|| {
            let (first, then) = if to.actions_first { (to, from) } else { (from, to) };
            format!(
                "{} runs the actions of the active steps before it tests the transitions, so a step's actions start in \
                 the call after it is entered and its outputs follow one call later than under {}'s rules, which fire \
                 the transitions first",
                first.name, then.name
            )
        })
    }

    /// The rules of the chart `chart` of a POU whose `sfc.dialect` is `dialect`.
    pub fn of(dialect: Option<&str>, chart: &Chart) -> RunRules {
        match dialect.map(|d| d.trim().to_ascii_lowercase()).as_deref() {
            Some("codesys") => RunRules { name: "CODESYS", final_run: true, first_call_tests: true, actions_first: true },
            Some("logix") => RunRules {
                name: "Studio 5000",
                final_run: chart.logix.last_scan == LastScan::ProgrammaticReset,
                first_call_tests: true,
                actions_first: true,
            },
            Some("graph") => RunRules { name: "S7-GRAPH", final_run: false, first_call_tests: false, actions_first: false },
            _ => RunRules { name: "IEC 61131-3", final_run: true, first_call_tests: false, actions_first: false },
        }
    }
}

/// What a step's actions do in the step's last scan (Logix's "Last Scan of Active Steps").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LastScan {
    /// "Don't scan" (`DontScan`, Studio 5000's default): only P and P0 actions execute.
    #[default]
    DontScan,
    /// "Programmatic reset" (`ProgrammaticReset`): every action executes, its Q bit off.
    ProgrammaticReset,
    /// "Automatic reset" (`AutomaticReset`): actions execute in postscan mode.
    AutomaticReset,
}

impl LastScan {
    /// The value as L5X and the `sfc.logix.lastscan` attribute write it.
    pub fn name(self) -> &'static str {
        match self {
            LastScan::DontScan => "DontScan",
            LastScan::ProgrammaticReset => "ProgrammaticReset",
            LastScan::AutomaticReset => "AutomaticReset",
        }
    }
}

/// The chart of one POU.
#[derive(Debug, Clone, PartialEq)]
pub struct Chart {
    /// Index of the file (in the check result) and of the POU among the file's items.
    pub file: u32,
    pub item: usize,
    pub pou: String,
    pub pou_kind: ast::PouKind,
    /// The action written in SFC whose body this chart is (CODESYS's SFC action); `None` for
    /// the POU's body. Its actions are the POU's actions that its steps name.
    pub action: Option<String>,
    pub target: Target,
    pub steps: Vec<StepNode>,
    pub transitions: Vec<TransitionNode>,
    pub actions: Vec<ActionNode>,
    pub name_span: Span,
    pub span: Span,
    /// The POU's Studio 5000 execution settings (defaults when it has none).
    pub logix: LogixSettings,
    /// The POU's S7-GRAPH block settings (defaults when it has none).
    pub s7graph: GraphSettings,
}

impl Chart {
    /// Case-insensitive step lookup.
    pub fn step(&self, name: &str) -> Option<StepId> {
        self.steps.iter().position(|s| s.name.eq_ignore_ascii_case(name))
    }
    pub fn transition(&self, name: &str) -> Option<TransitionId> {
        self.transitions.iter().position(|t| t.name.eq_ignore_ascii_case(name))
    }
    pub fn action(&self, name: &str) -> Option<ActionId> {
        self.actions.iter().position(|a| a.name.eq_ignore_ascii_case(name))
    }
    /// Transitions leaving a step, in declaration order.
    pub fn outgoing(&self, s: StepId) -> Vec<TransitionId> {
        (0..self.transitions.len()).filter(|&t| self.transitions[t].from.contains(&s)).collect()
    }
    /// Transitions entering a step, in declaration order.
    pub fn incoming(&self, s: StepId) -> Vec<TransitionId> {
        (0..self.transitions.len()).filter(|&t| self.transitions[t].to.contains(&s)).collect()
    }
    pub fn initial_steps(&self) -> Vec<StepId> {
        (0..self.steps.len()).filter(|&s| self.steps[s].initial).collect()
    }
    /// Outgoing and incoming transitions of every step, computed in one pass.
    pub fn adjacency(&self) -> Adjacency {
        let mut outgoing = vec![Vec::new(); self.steps.len()];
        let mut incoming = vec![Vec::new(); self.steps.len()];
        for (t, tr) in self.transitions.iter().enumerate() {
            for &s in &tr.from {
                outgoing[s].push(t);
            }
            for &s in &tr.to {
                incoming[s].push(t);
            }
        }
        Adjacency { outgoing, incoming }
    }
    /// Every divergence and convergence, steps first, then transitions, in declaration order.
    pub fn branches(&self) -> Vec<Branch> {
        let mut out = Vec::new();
        let adj = self.adjacency();
        for s in 0..self.steps.len() {
            let o = &adj.outgoing[s];
            if o.len() > 1 {
                out.push(Branch::SelectionDivergence { step: s, transitions: o.clone() });
            }
            let i = &adj.incoming[s];
            if i.len() > 1 {
                out.push(Branch::SelectionConvergence { step: s, transitions: i.clone() });
            }
        }
        for (t, tr) in self.transitions.iter().enumerate() {
            if tr.to.len() > 1 {
                out.push(Branch::SimultaneousDivergence { transition: t, steps: tr.to.clone() });
            }
            if tr.from.len() > 1 {
                out.push(Branch::SimultaneousConvergence { transition: t, steps: tr.from.clone() });
            }
        }
        out
    }
    /// Connected networks of steps (steps linked through transitions), each sorted.
    pub fn networks(&self) -> Vec<Vec<StepId>> {
        let n = self.steps.len();
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for t in &self.transitions {
            let all: Vec<StepId> = t.from.iter().chain(t.to.iter()).copied().collect();
            for w in all.windows(2) {
                let (a, b) = (find(&mut parent, w[0]), find(&mut parent, w[1]));
                if a != b {
                    parent[a] = b;
                }
            }
        }
        let mut groups: Vec<(usize, Vec<StepId>)> = Vec::new();
        for s in 0..n {
            let r = find(&mut parent, s);
            match groups.iter_mut().find(|g| g.0 == r) {
                Some(g) => g.1.push(s),
                None => groups.push((r, vec![s])),
            }
        }
        groups.into_iter().map(|g| g.1).collect()
    }
    /// Whether more than one step can be active: simultaneous branches, or several networks
    /// each with its initial step.
    pub fn several_active_steps(&self) -> bool {
        self.transitions.iter().any(|t| t.from.len() > 1 || t.to.len() > 1) || self.initial_steps().len() > 1
    }
    /// ATMT/EATMT state numbers (interfaces.md): tags where given; an untagged initial step is
    /// state 0 wherever it is declared (the first one in declaration order, when no tag takes 0);
    /// the other untagged steps take the free numbers in declaration order.
    pub fn state_numbers(&self) -> Vec<u32> {
        let mut used: std::collections::HashSet<u32> = self.steps.iter().filter_map(|s| s.tag).collect();
        let zero = if used.contains(&0) { None } else { self.steps.iter().position(|s| s.initial && s.tag.is_none()) };
        if zero.is_some() {
            used.insert(0);
        }
        let mut next = 0u32;
        self.steps
            .iter()
            .enumerate()
            .map(|(i, s)| match s.tag {
                Some(t) => t,
                None if Some(i) == zero => 0,
                None => {
                    while used.contains(&next) {
                        next += 1;
                    }
                    next += 1;
                    next - 1
                }
            })
            .collect()
    }
}
