//! The abstract syntax tree of an IEC 61131-3 source file.
//!
//! Every node carries its [`Span`]. Comments and pragmas are not nodes: they are kept, in
//! source order, in [`SourceUnit::trivia`], and the printer puts each one back before the first
//! node that starts after it. `sfc.*` attribute pragmas are additionally parsed and attached to the
//! element that follows them ([`Attribute`]). Together with the token stream (which covers every
//! byte of the input) this keeps the file lossless for `sfc fmt`.

pub use sfc_diagnostics::Span;

/// An identifier as written; compare with [`Ident::key`] (identifiers are case-insensitive).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ident {
    pub text: String,
    pub span: Span,
}

impl Ident {
    pub fn new(text: impl Into<String>, span: Span) -> Self {
        Ident { text: text.into(), span }
    }
    /// The case-folded form used for name resolution.
    pub fn key(&self) -> String {
        self.text.to_ascii_uppercase()
    }
    /// Case-insensitive comparison with a name.
    pub fn is(&self, name: &str) -> bool {
        self.text.eq_ignore_ascii_case(name)
    }
}

/// A comment or a pragma, kept for the printer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Trivia {
    pub kind: TriviaKind,
    /// The exact source text, delimiters included.
    pub text: String,
    pub span: Span,
    /// True when only white space precedes it on its line (it starts a line).
    pub own_line: bool,
    /// Its 0-based column (in characters) in the source, so the lines of a multi-line comment
    /// keep their alignment when the printer moves it.
    pub column: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TriviaKind {
    /// `(* … *)`
    BlockComment,
    /// `// …` (IEC 3rd edition line comment)
    LineComment,
    /// `{ … }`
    Pragma,
}

/// `{attribute 'name' := 'value'}` attached to the element that follows it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Attribute {
    pub name: String,
    pub value: Option<String>,
    /// Span of the whole pragma.
    pub span: Span,
}

/// A parsed file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SourceUnit {
    pub items: Vec<Item>,
    pub trivia: Vec<Trivia>,
    /// Byte offsets of the blank lines of the source (white space holding two or more line
    /// breaks), in order, so the printer can keep the user's grouping of statements.
    pub blank_lines: Vec<u32>,
    pub span: Span,
}

/// A top-level declaration.
#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    Pou(Pou),
    Types(TypeBlock),
    /// `VAR_GLOBAL … END_VAR` at file level.
    Globals(VarBlock),
    /// `CONFIGURATION … END_CONFIGURATION` and other blocks that are recognised, kept verbatim
    /// for the printer, and not analysed.
    Verbatim(Verbatim),
    /// `INTERFACE I_Cyl [EXTENDS I_Base, …] … END_INTERFACE` (IEC 61131-3 3rd edition).
    Interface(Interface),
}

impl Item {
    pub fn span(&self) -> Span {
        match self {
            Item::Pou(p) => p.span,
            Item::Types(t) => t.span,
            Item::Globals(v) => v.span,
            Item::Verbatim(v) => v.span,
            Item::Interface(i) => i.span,
        }
    }
}

/// A block kept as source text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Verbatim {
    /// The opening keyword, e.g. `CONFIGURATION`, or `PROGRAM`, `FUNCTION_BLOCK`, `FUNCTION`
    /// for a POU kept as written (one with an `sfc.verbatim` attribute, which says why).
    pub keyword: String,
    /// The attribute pragmas before it.
    pub attributes: Vec<Attribute>,
    pub name: Option<Ident>,
    pub text: String,
    pub span: Span,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PouKind {
    Program,
    FunctionBlock,
    Function,
}

impl PouKind {
    pub fn keyword(self) -> &'static str {
        match self {
            PouKind::Program => "PROGRAM",
            PouKind::FunctionBlock => "FUNCTION_BLOCK",
            PouKind::Function => "FUNCTION",
        }
    }
    pub fn end_keyword(self) -> &'static str {
        match self {
            PouKind::Program => "END_PROGRAM",
            PouKind::FunctionBlock => "END_FUNCTION_BLOCK",
            PouKind::Function => "END_FUNCTION",
        }
    }
}

/// A program organisation unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Pou {
    pub kind: PouKind,
    pub name: Ident,
    /// `FUNCTION F : INT`
    pub return_type: Option<TypeSpec>,
    pub attributes: Vec<Attribute>,
    pub var_blocks: Vec<VarBlock>,
    pub body: Body,
    /// The actions of a POU whose body is not a chart (CODESYS's actions of a PROGRAM or
    /// FUNCTION_BLOCK written in ST or IL: `ACTION Extend: … END_ACTION` after the body's
    /// statements, called `Extend();` inside the POU and `inst.Extend();` from outside). A
    /// chart's actions are elements of the chart (`Body::Sfc`); [`Pou::actions`] iterates both.
    pub actions: Vec<Action>,
    /// `ABSTRACT`, `FINAL`, `PUBLIC`, `INTERNAL` after the POU keyword, as written.
    pub modifiers: Vec<Ident>,
    /// `FUNCTION_BLOCK FB_Cyl EXTENDS FB_Base`
    pub extends: Option<Ident>,
    /// `IMPLEMENTS I_Cyl, I_Other`
    pub implements: Vec<Ident>,
    /// The methods of a FUNCTION_BLOCK (or PROGRAM, as CODESYS allows), in source order.
    pub methods: Vec<Method>,
    /// The properties (CODESYS, TwinCAT), in source order.
    pub properties: Vec<Property>,
    pub span: Span,
}

impl Pou {
    /// Whether the POU holds a chart: its body, or an action written in SFC.
    pub fn has_chart(&self) -> bool {
        matches!(self.body, Body::Sfc(_)) || self.actions().any(|a| matches!(a.body, ActionBody::Sfc(_)))
    }

    /// The steps of the POU's charts: its body's, then those of its actions written in SFC
    /// (one namespace: step names are unique within the POU).
    pub fn all_steps(&self) -> impl Iterator<Item = &Step> {
        let body = self.body.sfc().unwrap_or_default().iter();
        let actions = self.actions().flat_map(|a| a.body.sfc().unwrap_or_default().iter());
        body.chain(actions).filter_map(|e| match e {
            SfcElement::Step(s) => Some(s),
            _ => None,
        })
    }

    /// Every action of the POU: the chart's, or those after a non-chart body.
    pub fn actions(&self) -> impl Iterator<Item = &Action> {
        let chart = self.body.sfc().unwrap_or_default().iter().filter_map(|e| match e {
            SfcElement::Action(a) => Some(a),
            _ => None,
        });
        chart.chain(self.actions.iter())
    }
}

// ---------------------------------------------------------------------------------------------
// Objects: IEC 61131-3 3rd edition's methods and interfaces, CODESYS's properties

/// `METHOD [PUBLIC|PRIVATE|PROTECTED|INTERNAL] [ABSTRACT|FINAL] Name [: Type] … END_METHOD`
#[derive(Debug, Clone, PartialEq)]
pub struct Method {
    pub name: Ident,
    /// Access specifier and modifiers, as written.
    pub modifiers: Vec<Ident>,
    pub return_type: Option<TypeSpec>,
    pub attributes: Vec<Attribute>,
    pub var_blocks: Vec<VarBlock>,
    /// The statements (none in an INTERFACE, or for an ABSTRACT method).
    pub body: Body,
    pub span: Span,
}

/// `PROPERTY [PUBLIC|…] Name : Type GET … END_GET SET … END_SET END_PROPERTY`: CODESYS's
/// property, a pair of methods read and written as a variable of the instance.
#[derive(Debug, Clone, PartialEq)]
pub struct Property {
    pub name: Ident,
    pub modifiers: Vec<Ident>,
    pub ty: TypeSpec,
    pub attributes: Vec<Attribute>,
    /// `GET … END_GET`: its locals and statements; the value is assigned to the property name.
    pub get: Option<Accessor>,
    /// `SET … END_SET`: the new value is read through the property name.
    pub set: Option<Accessor>,
    pub span: Span,
}

/// One accessor of a [`Property`].
#[derive(Debug, Clone, PartialEq)]
pub struct Accessor {
    pub modifiers: Vec<Ident>,
    pub attributes: Vec<Attribute>,
    pub var_blocks: Vec<VarBlock>,
    pub body: Body,
    pub span: Span,
}

/// `INTERFACE I_Cyl [EXTENDS I_Base, …]`: method and property prototypes.
#[derive(Debug, Clone, PartialEq)]
pub struct Interface {
    pub name: Ident,
    pub attributes: Vec<Attribute>,
    pub extends: Vec<Ident>,
    pub methods: Vec<Method>,
    pub properties: Vec<Property>,
    pub span: Span,
}

/// The body of a POU.
#[derive(Debug, Clone, PartialEq)]
pub enum Body {
    /// Structured Text statements.
    St(Vec<Stmt>),
    /// Instruction List.
    Il(IlBody),
    /// Sequential Function Chart elements in source order.
    Sfc(Vec<SfcElement>),
}

impl Body {
    pub fn sfc_mut(&mut self) -> Option<&mut Vec<SfcElement>> {
        match self {
            Body::Sfc(e) => Some(e),
            _ => None,
        }
    }

    pub fn sfc(&self) -> Option<&[SfcElement]> {
        match self {
            Body::Sfc(e) => Some(e),
            _ => None,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Declarations

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum VarKind {
    Var,
    Input,
    Output,
    InOut,
    Global,
    External,
    Access,
    Temp,
}

impl VarKind {
    pub fn keyword(self) -> &'static str {
        match self {
            VarKind::Var => "VAR",
            VarKind::Input => "VAR_INPUT",
            VarKind::Output => "VAR_OUTPUT",
            VarKind::InOut => "VAR_IN_OUT",
            VarKind::Global => "VAR_GLOBAL",
            VarKind::External => "VAR_EXTERNAL",
            VarKind::Access => "VAR_ACCESS",
            VarKind::Temp => "VAR_TEMP",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Retain {
    Retain,
    NonRetain,
}

/// `VAR [CONSTANT] [RETAIN|NON_RETAIN] [PERSISTENT] … END_VAR`
#[derive(Debug, Clone, PartialEq)]
pub struct VarBlock {
    pub kind: VarKind,
    pub constant: bool,
    pub retain: Option<Retain>,
    /// `PERSISTENT` (CODESYS, TwinCAT): the values survive a cold start too.
    pub persistent: bool,
    pub decls: Vec<VarDecl>,
    pub span: Span,
}

/// `a, b AT %IX1 : BOOL := TRUE;` (names may be empty for `AT %IW6.2 : WORD;`).
#[derive(Debug, Clone, PartialEq)]
pub struct VarDecl {
    pub names: Vec<Ident>,
    pub location: Option<DirectAddress>,
    /// VAR_ACCESS: the access path between the name and the type, as written.
    pub access_path: Option<String>,
    /// VAR_ACCESS: `READ_ONLY` or `READ_WRITE`, as written.
    pub access_mode: Option<String>,
    pub ty: TypeSpec,
    pub init: Option<Initializer>,
    /// `Start : BOOL R_EDGE;`: an input that is TRUE for the call in which it rose (fell).
    pub edge: Option<Edge>,
    pub attributes: Vec<Attribute>,
    pub span: Span,
}

/// The edge of an edge-triggered input (`R_EDGE`, `F_EDGE`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Edge {
    Rising,
    Falling,
}

impl Edge {
    pub fn keyword(self) -> &'static str {
        match self {
            Edge::Rising => "R_EDGE",
            Edge::Falling => "F_EDGE",
        }
    }
}

/// `TYPE … END_TYPE`
#[derive(Debug, Clone, PartialEq)]
pub struct TypeBlock {
    pub decls: Vec<TypeDecl>,
    pub span: Span,
}

/// `Name : spec [:= init];`
#[derive(Debug, Clone, PartialEq)]
pub struct TypeDecl {
    pub name: Ident,
    pub spec: TypeSpec,
    pub init: Option<Initializer>,
    pub span: Span,
}

/// A type as written in a declaration.
#[derive(Debug, Clone, PartialEq)]
pub struct TypeSpec {
    pub kind: TypeSpecKind,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum TypeSpecKind {
    /// An elementary type, a derived type or a function block type, by name.
    Named(Ident),
    /// `STRING`, `STRING[10]`, `WSTRING(20)`
    String { wide: bool, length: Option<Box<Expr>> },
    /// `ARRAY [1..2, 1..3] OF INT` (also `ARRAY [1..2][1..3] OF INT`)
    Array { ranges: Vec<(Expr, Expr)>, element: Box<TypeSpec> },
    /// `INT (0..100)`
    Subrange { base: Ident, low: Box<Expr>, high: Box<Expr> },
    /// `(Red, Green := 2, Blue)`; `base` for `INT (A := 1, B := 2)` typed enums.
    Enum { base: Option<Ident>, values: Vec<(Ident, Option<Expr>)> },
    /// `STRUCT a : INT; b : BOOL := TRUE; END_STRUCT`
    Struct(Vec<VarDecl>),
    /// `POINTER TO INT`, `REFERENCE TO INT` (CODESYS), `REF_TO INT` (IEC 61131-3 3rd edition).
    Indirect { kind: Indirection, target: Box<TypeSpec> },
    /// Placeholder after a syntax error (a diagnostic has been reported).
    Error,
}

/// How a [`TypeSpecKind::Indirect`] is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Indirection {
    /// `POINTER TO`
    Pointer,
    /// `REFERENCE TO`
    Reference,
    /// `REF_TO`
    RefTo,
}

impl Indirection {
    pub fn keyword(self) -> &'static str {
        match self {
            Indirection::Pointer => "POINTER TO",
            Indirection::Reference => "REFERENCE TO",
            Indirection::RefTo => "REF_TO",
        }
    }
}

/// An initial value.
#[derive(Debug, Clone, PartialEq)]
pub enum Initializer {
    Expr(Expr),
    /// `[10(1), 2, 3(4)]`
    Array {
        elements: Vec<ArrayInitElement>,
        span: Span,
    },
    /// `(a := 1, b := (c := 2))`
    Struct {
        fields: Vec<(Ident, Initializer)>,
        span: Span,
    },
}

impl Initializer {
    pub fn span(&self) -> Span {
        match self {
            Initializer::Expr(e) => e.span,
            Initializer::Array { span, .. } | Initializer::Struct { span, .. } => *span,
        }
    }
}

/// `value` or `count(value)` or `count()` inside an array initialiser.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayInitElement {
    pub repeat: Option<Expr>,
    pub value: Option<Initializer>,
    pub span: Span,
}

/// `%IX2.4`, `%QW29`, `%MW6`, `%I*` (a partly specified address in a declaration).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DirectAddress {
    /// `I`, `Q` or `M`.
    pub area: char,
    /// `X`, `B`, `W`, `D`, `L`, or `X` when omitted (one bit).
    pub size: char,
    /// Whether the size letter was written.
    pub size_written: bool,
    /// The dot-separated unsigned integers; empty for `%I*`.
    pub path: Vec<u32>,
    pub text: String,
    pub span: Span,
}

// ---------------------------------------------------------------------------------------------
// SFC

/// One element of an SFC body, in source order.
#[derive(Debug, Clone, PartialEq)]
pub enum SfcElement {
    Step(Step),
    Transition(Transition),
    Action(Action),
}

impl SfcElement {
    pub fn span(&self) -> Span {
        match self {
            SfcElement::Step(s) => s.span,
            SfcElement::Transition(t) => t.span,
            SfcElement::Action(a) => a.span,
        }
    }
}

/// `STEP name: associations END_STEP` or `INITIAL_STEP …`
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    pub initial: bool,
    pub name: Ident,
    pub associations: Vec<ActionAssociation>,
    /// CODESYS's step actions (`ENTRY_ACTION := A;`, `STEP_ACTION := B;`, `EXIT_ACTION := C;`),
    /// beside the IEC associations.
    pub step_actions: Vec<StepAction>,
    pub attributes: Vec<Attribute>,
    /// Conditions a vendor attaches to a step, written as attributes whose value is an ST
    /// expression ([`STEP_CONDITIONS`]: S7-GRAPH's interlock and supervision), parsed where
    /// they stand in the text.
    pub conditions: Vec<StepCondition>,
    pub span: Span,
}

/// The attributes of a step whose value is a BOOL condition in ST: S7-GRAPH's interlock (the
/// step's interlock-dependent actions run only while it is TRUE) and supervision (TRUE is a
/// supervision error that holds the step), kept by the SimaticML import.
pub const STEP_CONDITIONS: &[&str] = &["sfc.s7graph.interlock", "sfc.s7graph.supervision"];

/// A step condition ([`STEP_CONDITIONS`]): the attribute's name as written and its expression.
#[derive(Debug, Clone, PartialEq)]
pub struct StepCondition {
    pub attribute: String,
    pub expr: Expr,
}

/// Which step action: CODESYS runs the entry action when the step becomes active, the step
/// (main) action every scan while it is active, the exit action once when it is left.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StepActionKind {
    Entry,
    Main,
    Exit,
}

impl StepActionKind {
    pub const ALL: [StepActionKind; 3] = [StepActionKind::Entry, StepActionKind::Main, StepActionKind::Exit];

    /// The word the text writes it with.
    pub fn keyword(self) -> &'static str {
        match self {
            StepActionKind::Entry => "ENTRY_ACTION",
            StepActionKind::Main => "STEP_ACTION",
            StepActionKind::Exit => "EXIT_ACTION",
        }
    }

    pub fn from_keyword(word: &str) -> Option<StepActionKind> {
        StepActionKind::ALL.into_iter().find(|k| k.keyword().eq_ignore_ascii_case(word))
    }

    /// In words: "entry", "step", "exit".
    pub fn word(self) -> &'static str {
        match self {
            StepActionKind::Entry => "entry",
            StepActionKind::Main => "step",
            StepActionKind::Exit => "exit",
        }
    }
}

/// `ENTRY_ACTION := Reset_Timer;` or `STEP_ACTION := Motor.ACT_Stop;` inside a step: the action
/// of the POU, or an action of one of its instances, that the step runs.
#[derive(Debug, Clone, PartialEq)]
pub struct StepAction {
    pub kind: StepActionKind,
    /// The action: a name, or `instance.Action`.
    pub action: Expr,
    pub span: Span,
}

impl StepAction {
    /// The call that runs it: `Name()` or `instance.Action()`.
    pub fn call(&self) -> Option<Expr> {
        let kind = match &self.action.kind {
            ExprKind::Name(id) => ExprKind::Call { callee: id.clone(), args: Vec::new() },
            ExprKind::Member { base, member } => {
                ExprKind::MemberCall { base: base.clone(), member: member.clone(), args: Vec::new() }
            }
            _ => return None,
        };
        Some(Expr { kind, span: self.action.span })
    }

    /// The action as written: `Name` or `instance.Action`.
    pub fn name(&self) -> String {
        fn path(e: &Expr, out: &mut String) {
            match &e.kind {
                ExprKind::Name(id) => out.push_str(&id.text),
                ExprKind::Member { base, member } => {
                    path(base, out);
                    out.push('.');
                    out.push_str(&member.text);
                }
                _ => {}
            }
        }
        let mut out = String::new();
        path(&self.action, &mut out);
        out
    }
}

/// `Action(Qualifier, T#5s, Indicator);`
#[derive(Debug, Clone, PartialEq)]
pub struct ActionAssociation {
    /// An action of the POU, a BOOL variable, or an action of an instance (`Motor.Stop`,
    /// CODESYS), whose IEC action control calls `Motor.Stop()`.
    pub action: Ident,
    /// As written (`N`, `SD`, …); `None` means the null qualifier (= N).
    pub qualifier: Option<Ident>,
    /// A TIME literal or a variable name.
    pub duration: Option<Expr>,
    pub indicators: Vec<Ident>,
    pub span: Span,
}

impl ActionAssociation {
    /// For an action of an instance (`Motor.Stop`, `Table.Motor.Stop`), the call that runs it.
    pub fn instance_call(&self) -> Option<Expr> {
        let text = &self.action.text;
        let (path, last) = text.rsplit_once('.')?;
        let span = self.action.span;
        let mut parts = path.split('.');
        let mut base = Expr { kind: ExprKind::Name(Ident::new(parts.next()?, span)), span };
        for p in parts {
            base = Expr { kind: ExprKind::Member { base: Box::new(base), member: Ident::new(p, span) }, span };
        }
        let member = Ident::new(last, span);
        Some(Expr { kind: ExprKind::MemberCall { base: Box::new(base), member, args: Vec::new() }, span })
    }
}

/// `TRANSITION [name] [(PRIORITY := n)] FROM … TO … := cond; END_TRANSITION`
#[derive(Debug, Clone, PartialEq)]
pub struct Transition {
    pub name: Option<Ident>,
    pub priority: Option<Box<Expr>>,
    pub from: Vec<Ident>,
    /// Whether FROM was written with parentheses (kept for the printer).
    pub from_parens: bool,
    pub to: Vec<Ident>,
    pub to_parens: bool,
    pub condition: Condition,
    pub attributes: Vec<Attribute>,
    pub span: Span,
}

/// The condition of a transition.
#[derive(Debug, Clone, PartialEq)]
pub enum Condition {
    /// `:= expr;`
    St(Expr),
    /// `: LD a AND b` (the IL current result is the condition).
    Il(IlBody),
    /// Nothing usable was written (a diagnostic has been reported).
    Missing,
}

/// `ACTION name: body END_ACTION`
#[derive(Debug, Clone, PartialEq)]
pub struct Action {
    pub name: Ident,
    pub body: ActionBody,
    pub attributes: Vec<Attribute>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ActionBody {
    St(Vec<Stmt>),
    Il(IlBody),
    /// A chart inside an action (CODESYS's SFC action): its own initial step, steps and
    /// transitions, whose associations name the POU's actions. Step names are unique within
    /// the POU. Calling the action (or an association of it) runs one scan of this chart.
    Sfc(Vec<SfcElement>),
}

impl ActionBody {
    /// The chart of an action written in SFC.
    pub fn sfc(&self) -> Option<&[SfcElement]> {
        match self {
            ActionBody::Sfc(e) => Some(e),
            _ => None,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Structured Text

#[derive(Debug, Clone, PartialEq)]
/// (Large fields are boxed so a statement stays small: bodies of big charts are long lists.)
pub struct Stmt {
    pub kind: StmtKind,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum StmtKind {
    /// `target := value;`
    Assign {
        target: Box<Expr>,
        value: Box<Expr>,
    },
    /// A call used as a statement: `Timer(IN := x, PT := T#1s);`, `F(1);`
    Call(Box<Expr>),
    /// `r REF= x;`: the reference `r` made to designate `x` (CODESYS).
    RefAssign {
        target: Box<Expr>,
        value: Box<Expr>,
    },
    /// `IF c THEN … ELSIF c THEN … ELSE … END_IF`
    If {
        branches: Vec<(Expr, Vec<Stmt>)>,
        else_body: Option<Vec<Stmt>>,
    },
    /// `CASE sel OF 1, 2..5: … ELSE … END_CASE`
    Case {
        selector: Box<Expr>,
        arms: Vec<CaseArm>,
        else_body: Option<Vec<Stmt>>,
    },
    /// `FOR i := a TO b BY c DO … END_FOR`
    For {
        var: Ident,
        from: Box<Expr>,
        to: Box<Expr>,
        by: Option<Box<Expr>>,
        body: Vec<Stmt>,
    },
    /// `WHILE c DO … END_WHILE`
    While {
        cond: Box<Expr>,
        body: Vec<Stmt>,
    },
    /// `REPEAT … UNTIL c END_REPEAT`
    Repeat {
        body: Vec<Stmt>,
        until: Box<Expr>,
    },
    Exit,
    Return,
    /// A lone `;`.
    Empty,
}

#[derive(Debug, Clone, PartialEq)]
pub struct CaseArm {
    pub labels: Vec<CaseLabel>,
    pub body: Vec<Stmt>,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum CaseLabel {
    Value(Expr),
    Range(Expr, Expr),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    Literal(Literal),
    /// A variable, step, action, enumerated value or constant.
    Name(Ident),
    /// `%IX2.4` used directly in code.
    Address(DirectAddress),
    /// `base.member` (struct field, FB output, `Step.X`, `Step.T`, `Action.Q`); also bit access
    /// `w.3` with `member` = "3".
    Member {
        base: Box<Expr>,
        member: Ident,
    },
    /// `a[i, j]`
    Index {
        base: Box<Expr>,
        indices: Vec<Expr>,
    },
    /// `F(1, 2)`, `Fb(IN := x, Q => y)`
    Call {
        callee: Ident,
        args: Vec<Arg>,
    },
    /// `inst.Act()`: a call of a member of `base` (an action of a function block instance;
    /// CODESYS's `Gripper.Close();`).
    MemberCall {
        base: Box<Expr>,
        member: Ident,
        args: Vec<Arg>,
    },
    Unary {
        op: UnaryOp,
        operand: Box<Expr>,
    },
    Binary {
        op: BinaryOp,
        lhs: Box<Expr>,
        rhs: Box<Expr>,
    },
    /// `( e )`, kept so the printer reproduces the user's grouping.
    Paren(Box<Expr>),
    /// `p^`: what a pointer or reference points to (`THIS^`, `SUPER^`).
    Deref(Box<Expr>),
    /// Placeholder after a syntax error (a diagnostic has been reported).
    Error,
}

/// One argument of a call.
#[derive(Debug, Clone, PartialEq)]
pub struct Arg {
    /// Formal parameter name, if written (`IN := x`, `Q => y`).
    pub name: Option<Ident>,
    /// `=>`: an output binding.
    pub output: bool,
    /// `NOT Q => y` (negated output binding).
    pub negated: bool,
    /// The value (input) or the target (output); `None` for an empty output binding `Q =>`.
    pub value: Option<Expr>,
    pub span: Span,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum UnaryOp {
    Neg,
    Plus,
    Not,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BinaryOp {
    Or,
    OrElse,
    Xor,
    And,
    AndThen,
    Eq,
    Ne,
    Lt,
    Gt,
    Le,
    Ge,
    Add,
    Sub,
    Mul,
    Div,
    Mod,
    Pow,
}

impl BinaryOp {
    /// Binding power: larger binds tighter (IEC 61131-3 table 55).
    pub fn precedence(self) -> u8 {
        match self {
            BinaryOp::Or | BinaryOp::OrElse => 1,
            BinaryOp::Xor => 2,
            BinaryOp::And | BinaryOp::AndThen => 3,
            BinaryOp::Eq | BinaryOp::Ne => 4,
            BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge => 5,
            BinaryOp::Add | BinaryOp::Sub => 6,
            BinaryOp::Mul | BinaryOp::Div | BinaryOp::Mod => 7,
            BinaryOp::Pow => 9,
        }
    }
    /// The canonical spelling.
    pub fn symbol(self) -> &'static str {
        match self {
            BinaryOp::Or => "OR",
            BinaryOp::OrElse => "OR_ELSE",
            BinaryOp::Xor => "XOR",
            BinaryOp::And => "AND",
            BinaryOp::AndThen => "AND_THEN",
            BinaryOp::Eq => "=",
            BinaryOp::Ne => "<>",
            BinaryOp::Lt => "<",
            BinaryOp::Gt => ">",
            BinaryOp::Le => "<=",
            BinaryOp::Ge => ">=",
            BinaryOp::Add => "+",
            BinaryOp::Sub => "-",
            BinaryOp::Mul => "*",
            BinaryOp::Div => "/",
            BinaryOp::Mod => "MOD",
            BinaryOp::Pow => "**",
        }
    }
}

/// Precedence of unary operators (`-`, `NOT`): above `*` (7), below `**` (9).
pub const UNARY_PRECEDENCE: u8 = 8;

/// A literal with its optional type prefix (`INT#5`, `UINT#16#FE`, `STRING#'x'`).
#[derive(Debug, Clone, PartialEq)]
pub struct Literal {
    pub kind: LiteralKind,
    /// The elementary type name before `#`, upper-cased (`INT`, `BOOL`, …), if written.
    pub type_prefix: Option<String>,
    /// The source text, for the printer.
    pub text: String,
}

#[derive(Debug, Clone, PartialEq)]
pub enum LiteralKind {
    /// Integer value. A sign is a unary operator, except inside a typed literal (`INT#-5`).
    Int(i128),
    Real(f64),
    Bool(bool),
    /// Decoded characters; `wide` for `"…"`.
    String {
        value: String,
        wide: bool,
    },
    /// Microseconds (TIME / LTIME).
    Duration(i64),
    /// Days since 1970-01-01.
    Date(i64),
    /// Microseconds since midnight.
    TimeOfDay(i64),
    /// Microseconds since 1970-01-01T00:00:00.
    DateAndTime(i64),
    /// An enumerated value with its type: `Colour#Red` (`type_prefix` holds the type).
    Enum(Ident),
}

// ---------------------------------------------------------------------------------------------
// Instruction List

/// A list of IL instructions.
#[derive(Debug, Clone, PartialEq)]
pub struct IlBody {
    pub instructions: Vec<IlInstruction>,
    pub span: Span,
}

/// `[label:] OP[N][C][(] operand(s)` or a call.
#[derive(Debug, Clone, PartialEq)]
pub struct IlInstruction {
    pub label: Option<Ident>,
    /// The operator as written (`LD`, `ANDN`, `JMPC`, `CAL`, a function name, …); `None` for a
    /// line holding only a label, or for the closing `)` of a nested expression.
    pub op: Option<Ident>,
    /// Operands (`LD x`, `SEL G, a, b`, `JMP label` as a name).
    pub operands: Vec<Expr>,
    /// `AND( … )`: the nested instructions up to the matching `)`.
    pub nested: Option<Vec<IlInstruction>>,
    /// `CAL Fb(IN := x)`: the formal arguments.
    pub call_args: Option<Vec<Arg>>,
    pub span: Span,
}
