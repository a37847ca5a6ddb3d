//! Calls: standard and user functions, function block instances, actions.

use crate::check::{fit, untyped_phrase, Checker, Fit, Operand};
use crate::env::PouInterface;
use crate::scope::Sym;
use crate::stdlib::{std_function, ParamType, ReturnType, StdFunction, STD_FUNCTION_NAMES};
use crate::suggest::closest;
use crate::types::Type;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::ast::{Arg, Expr, ExprKind, Ident, VarKind};

/// What a called name refers to.
enum Callee {
    /// An instance of a function block (a variable of FB type).
    Instance(Sym, PouInterface),
    /// A variable that is not a function block instance.
    NotCallable(String),
    Action(Sym),
    UserFunction(PouInterface),
    Std(StdFunction),
    /// A function block type called directly (needs an instance).
    FbType(String),
    /// A method of the block whose code this is (`M(…)` for `THIS^.M(…)`).
    Method(crate::env::MethodSig),
    /// `SUPER^()`: the body of the base block.
    SuperBody,
    Unknown,
}

impl Checker<'_, '_> {
    fn callee(&self, name: &Ident) -> Callee {
        let env = self.scope.env();
        if name.text == "SUPER^" {
            let base = self.scope.pou_name().and_then(|p| env.function_block(p)).and_then(|fb| fb.base.clone());
            return match base {
                Some(_) => Callee::SuperBody,
                None => Callee::NotCallable(
                    "`SUPER^()` calls the body of the base block, and this block extends none".into(),
                ),
            };
        }
        match self.scope.resolve(&name.text) {
            Some(sym @ (Sym::Local(_) | Sym::Global(_))) => {
                let ty = self.scope.var_info(sym).map(|v| v.ty.clone()).unwrap_or(Type::Error);
                return match env.fb_of(&ty) {
                    Some(fb) => Callee::Instance(sym, fb.clone()),
                    None if ty.is_error() => Callee::Unknown,
                    None => Callee::NotCallable(format!("`{}` is a `{ty}` variable, not a function", name.text)),
                };
            }
            Some(sym @ Sym::Action(_)) => return Callee::Action(sym),
            Some(Sym::Step(_)) => return Callee::NotCallable(format!("`{}` is a step, not a function", name.text)),
            // Inside a FUNCTION its own name is the result variable; calling it is recursion,
            // which IEC 61131-3 forbids.
            Some(Sym::Return) => {
                return Callee::NotCallable(format!("function `{}` cannot call itself (recursion)", name.text))
            }
            None => {}
        }
        if let Some(m) = self.scope.pou_name().and_then(|p| env.function_block(p)).and_then(|fb| fb.method(&name.text))
        {
            return Callee::Method(m.clone());
        }
        if let Some(f) = env.function(&name.text) {
            return Callee::UserFunction(f.clone());
        }
        if let Some(f) = std_function(&name.text) {
            return Callee::Std(f);
        }
        if let Some(fb) = env.function_block(&name.text) {
            return Callee::FbType(fb.name.clone());
        }
        Callee::Unknown
    }

    fn unknown_callee(&mut self, name: &Ident) {
        let env = self.scope.env();
        let mut d = Diagnostic::new("SFC0306", name.span, format!("unknown function `{}`", name.text));
        let user = env.declared_names();
        let instances =
            self.scope.vars().iter().filter(|v| matches!(v.ty, Type::FunctionBlock(_))).map(|v| v.name.as_str());
        if let Some(s) = closest(&name.text, STD_FUNCTION_NAMES.iter().copied().chain(user).chain(instances)) {
            d = d.with_note(format!("did you mean `{s}`?"));
        }
        self.report(d);
    }

    /// Checks the argument values of a call that cannot be checked against a signature, so
    /// the names in them still count as used and their own errors are found.
    pub(crate) fn check_args_loosely(&mut self, args: &[Arg]) {
        for a in args {
            if let Some(v) = &a.value {
                if a.output {
                    self.target(v);
                } else {
                    self.check_expr(v, None);
                }
            }
        }
    }

    /// A call used as a value.
    pub(crate) fn call_value(&mut self, name: &Ident, args: &[Arg], span: Span, expected: Option<&Type>) -> Type {
        // CODESYS's `ADR(x)` (and IEC's `REF(x)`), unless the file declares a function so named.
        if (name.is("ADR") || name.is("REF"))
            && self.scope.resolve(&name.text).is_none()
            && self.scope.env().function(&name.text).is_none()
        {
            return self.adr(args, span);
        }
        // CODESYS's `SIZEOF(x)` and `SIZEOF(T)`, `__ISVALIDREF(r)`.
        if self.scope.resolve(&name.text).is_none() && self.scope.env().function(&name.text).is_none() {
            if name.is("SIZEOF") {
                return self.sizeof(args, span);
            }
            if name.is("__ISVALIDREF") {
                return self.is_valid_ref(args, span);
            }
            if name.is("LOWER_BOUND") || name.is("UPPER_BOUND") {
                self.bound(name, args, span);
                return Type::DInt;
            }
        }
        match self.callee(name) {
            Callee::Instance(sym, fb) => {
                self.fb_call(name, sym, &fb, args, span);
                if !self.in_guard {
                    self.error(
                        "SFC0302",
                        span,
                        format!(
                            "a function block call has no value; call `{}` as a statement and read its outputs",
                            name.text
                        ),
                    );
                }
                Type::Error
            }
            Callee::UserFunction(f) => {
                let t = self.user_call(&f, args, span);
                match t {
                    Some(t) => t,
                    None => {
                        self.error("SFC0302", span, format!("function `{}` returns no value", f.name));
                        Type::Error
                    }
                }
            }
            Callee::Std(f) => self.std_call(&f, args, span, expected),
            Callee::Method(m) => self.method_call(&m, args, span, true),
            other => {
                self.other_callee(name, other, args);
                Type::Error
            }
        }
    }

    /// `inst.Act()`: an action of the function block instance `base` (CODESYS's
    /// `Gripper.Close();`), called as a statement: it runs the action's body on the instance.
    pub(crate) fn member_call_stmt(&mut self, base: &Expr, member: &Ident, args: &[Arg], span: Span) {
        let ty = self.check_expr(base, None);
        if ty.is_error() {
            self.check_args_loosely(args);
            return;
        }
        let env = self.scope.env();
        // `itf.M(…)`: a method of the interface, run on the instance it designates.
        if let Type::Interface(i) = &ty {
            match env.interface(i).map(|itf| (itf.method(&member.text).cloned(), itf)) {
                Some((Some(m), _)) => {
                    self.method_call(&m, args, span, false);
                }
                Some((None, itf)) => {
                    let mut d = Diagnostic::new(
                        "SFC0306",
                        member.span,
                        format!("interface `{}` has no method `{}`", itf.name, member.text),
                    );
                    if let Some(s) = closest(&member.text, itf.methods.iter().map(|m| m.name.as_str())) {
                        d = d.with_note(format!("did you mean `{s}`?"));
                    }
                    self.report(d);
                    self.check_args_loosely(args);
                }
                None => self.check_args_loosely(args),
            }
            return;
        }
        let fb = env.fb_of(&ty).cloned();
        // `inst.Inner(…)`: a call of a function block instance inside `inst` (CODESYS calls an
        // instance passed in an input so: `xPPU.Stack();`).
        let inner_ty = fb.as_ref().and_then(|fb| {
            let is_action = fb.actions.iter().any(|a| a.eq_ignore_ascii_case(&member.text));
            fb.var(&member.text).filter(|_| !is_action).map(|v| v.ty.clone())
        });
        // An instance of a block kept as written (a library's): not analysed.
        // (A member whose type is unknown has been reported where it is declared.)
        if matches!(&inner_ty, Some(Type::FunctionBlock(n)) if env.is_opaque(n))
            || inner_ty.as_ref().is_some_and(Type::is_error)
        {
            self.check_args_loosely(args);
            return;
        }
        if let Some(inner) = inner_ty.and_then(|t| env.fb_of(&t).cloned()) {
            let path = Expr {
                kind: ExprKind::Member { base: Box::new(base.clone()), member: member.clone() },
                span: Span::new(base.span.file, base.span.start, member.span.end),
            };
            if self.check_expr(&path, None).is_error() {
                self.check_args_loosely(args);
                return;
            }
            self.instance_call(member, &inner, args, span);
            return;
        }
        if let Some(m) = fb.as_ref().and_then(|fb| fb.method(&member.text)).cloned() {
            self.method_call(&m, args, span, false);
            return;
        }
        match fb {
            Some(fb) if fb.actions.iter().any(|a| a.eq_ignore_ascii_case(&member.text)) => {
                let sfc = fb.sfc_actions.iter().any(|a| a.eq_ignore_ascii_case(&member.text));
                self.action_args(&member.text, sfc, args, span);
            }
            Some(fb) => {
                let what = if fb.methods.is_empty() { "action" } else { "action or method" };
                let mut d = Diagnostic::new(
                    "SFC0306",
                    member.span,
                    format!("function block `{}` has no {what} `{}`", fb.name, member.text),
                );
                let known = fb.actions.iter().map(String::as_str).chain(fb.methods.iter().map(|m| m.name.as_str()));
                if let Some(s) = closest(&member.text, known) {
                    d = d.with_note(format!("did you mean `{s}`?"));
                } else if fb.actions.is_empty() {
                    d = d.with_note(format!("`{}` declares no actions", fb.name));
                }
                self.report(d);
                self.check_args_loosely(args);
            }
            // An instance of a block kept as written (a library's): not analysed.
            None if matches!(&ty, Type::FunctionBlock(n) if env.is_opaque(n)) => self.check_args_loosely(args),
            None => {
                let p = self.phrase(base, &ty);
                self.error("SFC0306", member.span, format!("`{}` is called, but its base is {p}", member.text));
                self.check_args_loosely(args);
            }
        }
    }

    /// A call used as a statement (`Timer(IN := x);`, `F(1);`, `Action();`, `inst.Act();`).
    pub fn call_stmt(&mut self, e: &Expr) {
        if let ExprKind::MemberCall { base, member, args } = &e.kind {
            self.member_call_stmt(base, member, args, e.span);
            return;
        }
        let ExprKind::Call { callee, args } = &e.kind else {
            self.check_expr(e, None);
            return;
        };
        match self.callee(callee) {
            Callee::Instance(sym, fb) => self.fb_call(callee, sym, &fb, args, e.span),
            Callee::UserFunction(f) => {
                self.user_call(&f, args, e.span);
            }
            Callee::Std(f) => {
                self.std_call(&f, args, e.span, None);
            }
            Callee::Method(m) => {
                self.method_call(&m, args, e.span, false);
            }
            Callee::SuperBody => {
                if !args.is_empty() {
                    self.error("SFC0307", e.span, "`SUPER^()` takes no arguments");
                }
            }
            Callee::Action(sym) => {
                self.scope.mark(sym, false);
                let env = self.scope.env();
                let sfc = self
                    .scope
                    .pou_name()
                    .and_then(|p| env.pou(p))
                    .is_some_and(|p| p.sfc_actions.iter().any(|a| a.eq_ignore_ascii_case(&callee.text)));
                self.action_args(&callee.text, sfc, args, e.span);
            }
            other => self.other_callee(callee, other, args),
        }
    }

    /// The arguments of a call of an action: none, or for an action written in SFC its chart's
    /// flags (`Act(SFCReset := TRUE)`, CODESYS), each a BOOL given by name.
    fn action_args(&mut self, action: &str, sfc: bool, args: &[Arg], span: Span) {
        if args.is_empty() {
            return;
        }
        if !sfc {
            self.error("SFC0307", span, format!("action `{action}` takes no arguments"));
            return;
        }
        for a in args {
            let flag = a.name.as_ref().filter(|n| crate::env::SFC_ACTION_FLAGS.iter().any(|f| n.is(f)));
            match (flag, &a.value) {
                (Some(_), Some(v)) if !a.output => {
                    let t = self.check_expr(v, Some(&Type::Bool));
                    if !t.assignable_to(&Type::Bool) {
                        let what = self.phrase(v, &t);
                        self.error(
                            "SFC0302",
                            v.span,
                            format!("type mismatch: a chart flag is BOOL, but the argument is {what}"),
                        );
                    }
                }
                _ => {
                    self.error(
                        "SFC0307",
                        a.span,
                        format!(
                            "the call of action `{action}` (written in SFC) sets only its chart's flags: {}",
                            crate::env::SFC_ACTION_FLAGS.map(|f| format!("`{f} := …`")).join(", ")
                        ),
                    );
                    if let Some(v) = &a.value {
                        self.check_expr(v, None);
                    }
                }
            }
        }
    }

    fn other_callee(&mut self, name: &Ident, callee: Callee, args: &[Arg]) {
        match callee {
            Callee::NotCallable(msg) => self.error("SFC0306", name.span, msg),
            Callee::Action(sym) => {
                self.scope.mark(sym, false);
                self.error("SFC0306", name.span, format!("action `{0}` has no value; its state is `{0}.Q`", name.text));
            }
            Callee::FbType(fb) => self.error(
                "SFC0306",
                name.span,
                format!("`{fb}` is a function block type; declare an instance (`Inst : {fb};`) and call that"),
            ),
            Callee::Unknown => {
                // An error-typed instance was already reported; a POU kept as written is not
                // analysed, nor are calls of it.
                match self.scope.resolve(&name.text) {
                    // An instance of an opaque block is used by calling it.
                    Some(sym @ (Sym::Local(_) | Sym::Global(_))) => self.scope.mark(sym, false),
                    None if !self.scope.env().is_opaque(&name.text) => self.unknown_callee(name),
                    _ => {}
                }
            }
            Callee::SuperBody => self.error("SFC0302", name.span, "`SUPER^()` has no value; call it as a statement"),
            Callee::Instance(..) | Callee::UserFunction(_) | Callee::Std(_) | Callee::Method(_) => {}
        }
        self.check_args_loosely(args);
    }

    /// Reports calls that mix formal and positional arguments; true when they do.
    fn mixed_args(&mut self, name: &str, args: &[Arg], span: Span) -> bool {
        let formal = args.iter().filter(|a| a.name.is_some()).count();
        if formal > 0 && formal < args.len() {
            self.error(
                "SFC0307",
                span,
                format!("the call of `{name}` mixes formal (`IN := …`) and positional arguments; use one style"),
            );
            return true;
        }
        false
    }

    /// `EN := …` and `ENO => …`, accepted on every call. True when `arg` was one.
    fn en_eno(&mut self, arg: &Arg) -> bool {
        let Some(n) = &arg.name else { return false };
        if n.is("EN") && !arg.output {
            if let Some(v) = &arg.value {
                let t = self.check_expr(v, Some(&Type::Bool));
                if !t.is_bool() && !t.is_error() {
                    let p = self.phrase(v, &t);
                    self.error("SFC0302", v.span, format!("type mismatch: `EN` is BOOL, but the argument is {p}"));
                }
            }
            return true;
        }
        if n.is("ENO") && arg.output {
            if let Some(v) = &arg.value {
                self.output_binding("ENO", &Type::Bool, v, arg.negated);
            }
            return true;
        }
        false
    }

    /// `param => target`: the output's value is assigned to the target.
    fn output_binding(&mut self, param: &str, ty: &Type, target: &Expr, negated: bool) {
        if self.in_guard {
            self.error(
                "SFC0305",
                target.span,
                format!(
                    "the output binding `{param} => {}` writes a variable in a transition condition",
                    crate::check::expr_text(target)
                ),
            );
        }
        let tt = self.target(target);
        if negated && !ty.is_bool() && !ty.is_error() {
            self.error("SFC0307", target.span, format!("only a BOOL output can be negated; `{param}` is `{ty}`"));
            return;
        }
        if !self.assignable(ty, &tt) {
            self.error(
                "SFC0302",
                target.span,
                format!(
                    "type mismatch: output `{param}` is `{ty}`, but `{}` is `{tt}`",
                    crate::check::expr_text(target)
                ),
            );
        }
    }

    /// `value` passed to input `param` of type `ty` of `owner`.
    fn input_binding(&mut self, owner: &str, param: &str, ty: &Type, value: &Expr) {
        let t = self.check_expr(value, Some(ty));
        if !self.assignable(&t, ty) {
            let p = self.phrase(value, &t);
            self.error(
                "SFC0302",
                value.span,
                format!("type mismatch: input `{param}` of `{owner}` is `{ty}`, but the argument is {p}"),
            );
        }
    }

    /// `value` passed to VAR_IN_OUT `param`: a variable of the same type.
    fn in_out_binding(&mut self, owner: &str, param: &str, ty: &Type, value: &Expr) {
        if !matches!(
            value.kind,
            ExprKind::Name(_)
                | ExprKind::Member { .. }
                | ExprKind::Index { .. }
                | ExprKind::Address(_)
                | ExprKind::Error
        ) {
            self.check_expr(value, None);
            self.error(
                "SFC0308",
                value.span,
                format!("in-out `{param}` of `{owner}` is passed by reference and needs a variable, not an expression"),
            );
            return;
        }
        let t = self.target(value);
        let same =
            t.is_error() || ty.is_error() || &t == ty || (t.is_string() && ty.is_string() && t.assignable_to(ty));
        if !same {
            self.error(
                "SFC0302",
                value.span,
                format!(
                    "type mismatch: in-out `{param}` of `{owner}` is `{ty}`, but `{}` is `{t}`",
                    crate::check::expr_text(value)
                ),
            );
        }
    }

    fn unknown_param(&mut self, owner: &str, name: &Ident, params: &[&str]) {
        let mut d = Diagnostic::new("SFC0307", name.span, format!("`{owner}` has no parameter `{}`", name.text));
        if let Some(s) = closest(&name.text, params.iter().copied()) {
            d = d.with_note(format!("did you mean `{s}`?"));
        }
        self.report(d);
    }

    /// Binds arguments to the parameters of a user POU (function or function block);
    /// `instance` names the called instance in messages.
    fn bind_pou_args(&mut self, owner: &str, pou: &PouInterface, args: &[Arg], span: Span, is_function: bool) {
        if self.mixed_args(owner, args, span) {
            self.check_args_loosely(args);
            return;
        }
        let positional: Vec<&crate::env::VarInfo> = pou.positional_params().collect();
        let param_names: Vec<&str> = pou
            .vars
            .iter()
            .filter(|v| matches!(v.kind, VarKind::Input | VarKind::Output | VarKind::InOut))
            .map(|v| v.name.as_str())
            .collect();
        let mut given: Vec<String> = Vec::new();
        let formal = args.iter().any(|a| a.name.is_some());
        if !formal && args.len() != positional.len() && (is_function || args.len() > positional.len()) {
            self.error(
                "SFC0307",
                span,
                format!(
                    "`{owner}` takes {} argument{}, but {} {} given",
                    positional.len(),
                    if positional.len() == 1 { "" } else { "s" },
                    args.len(),
                    if args.len() == 1 { "was" } else { "were" }
                ),
            );
            self.check_args_loosely(args);
            return;
        }
        for (i, arg) in args.iter().enumerate() {
            if self.en_eno(arg) {
                continue;
            }
            let param = match &arg.name {
                None => positional.get(i).copied(),
                Some(n) => {
                    let found = pou
                        .var(&n.text)
                        .filter(|v| matches!(v.kind, VarKind::Input | VarKind::Output | VarKind::InOut));
                    if found.is_none() {
                        self.unknown_param(owner, n, &param_names);
                        self.check_args_loosely(std::slice::from_ref(arg));
                        continue;
                    }
                    found
                }
            };
            let Some(param) = param else { continue };
            let key = param.name.to_ascii_uppercase();
            if given.contains(&key) {
                self.error("SFC0307", arg.span, format!("parameter `{}` is given twice", param.name));
                continue;
            }
            given.push(key);
            match (param.kind, arg.output) {
                (VarKind::Output, true) => {
                    if let Some(v) = &arg.value {
                        self.output_binding(&param.name, &param.ty, v, arg.negated);
                    }
                }
                (VarKind::Output, false) => {
                    self.error(
                        "SFC0307",
                        arg.span,
                        format!("`{}` is an output of `{}`; bind it with `=>`", param.name, pou.name),
                    );
                    self.check_args_loosely(std::slice::from_ref(arg));
                }
                (_, true) => {
                    self.error(
                        "SFC0307",
                        arg.span,
                        format!("`{}` is an input of `{}`; pass it with `:=`", param.name, pou.name),
                    );
                    self.check_args_loosely(std::slice::from_ref(arg));
                }
                (VarKind::InOut, false) => {
                    if let Some(v) = &arg.value {
                        self.in_out_binding(owner, &param.name, &param.ty, v);
                    }
                }
                (_, false) => {
                    if let Some(v) = &arg.value {
                        self.input_binding(owner, &param.name, &param.ty, v);
                    }
                }
            }
        }
        if formal {
            // In-outs refer to the caller's variable: they must be bound. Inputs keep their
            // previous (FB) or initial (function) value when omitted.
            let missing: Vec<String> = pou
                .in_outs()
                .filter(|v| !given.contains(&v.name.to_ascii_uppercase()))
                .map(|v| format!("`{}`", v.name))
                .collect();
            if !missing.is_empty() {
                self.error(
                    "SFC0307",
                    span,
                    format!("the call of `{owner}` must bind the in-out {}", missing.join(", ")),
                );
            }
        }
    }

    /// Binds the arguments of a method call to the method's parameters (as a function's; an
    /// omitted input keeps its initial value).
    pub(crate) fn bind_method_args(&mut self, m: &PouInterface, args: &[Arg], span: Span) {
        self.bind_pou_args(&m.name, m, args, span, false);
    }

    /// A call of a function block instance. In a transition condition it is a side effect.
    pub(crate) fn fb_call(&mut self, name: &Ident, sym: Sym, fb: &PouInterface, args: &[Arg], span: Span) {
        self.scope.mark(sym, false);
        self.scope.mark(sym, true);
        self.instance_call(name, fb, args, span);
    }

    /// The call of instance `name` of block `fb` (a variable, or `inst.Inner`): its arguments,
    /// and in a transition condition the side effect.
    fn instance_call(&mut self, name: &Ident, fb: &PouInterface, args: &[Arg], span: Span) {
        if self.in_guard {
            self.error(
                "SFC0305",
                span,
                format!(
                    "calling function block `{}` changes its state; call it in an action and test its outputs here",
                    name.text
                ),
            );
        }
        self.bind_pou_args(&name.text, fb, args, span, false);
    }

    /// A call of a user FUNCTION; its result type (`None` when it has none).
    fn user_call(&mut self, f: &PouInterface, args: &[Arg], span: Span) -> Option<Type> {
        self.bind_pou_args(&f.name, f, args, span, true);
        f.return_type.clone()
    }

    /// A call of a standard function, typed by its generic signature.
    pub(crate) fn std_call(&mut self, f: &StdFunction, args: &[Arg], span: Span, expected: Option<&Type>) -> Type {
        if self.mixed_args(&f.name, args, span) {
            self.check_args_loosely(args);
            return Type::Error;
        }
        // Bind each argument to a parameter index.
        let mut bound: Vec<(usize, &Expr)> = Vec::new();
        let mut bad = false;
        let mut positional = 0usize;
        for arg in args {
            if self.en_eno(arg) {
                continue;
            }
            let index = match &arg.name {
                None => {
                    positional += 1;
                    positional - 1
                }
                Some(n) => match f.param_index(&n.text) {
                    Some(i) => i,
                    None => {
                        let names: Vec<String> = (0..f.params.len()).filter_map(|i| f.param_name(i)).collect();
                        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
                        self.unknown_param(&f.name, n, &refs);
                        bad = true;
                        continue;
                    }
                },
            };
            if arg.output {
                let pname = f.param_name(index).unwrap_or_default();
                self.error("SFC0307", arg.span, format!("`{pname}` is an input of `{}`; pass it with `:=`", f.name));
                bad = true;
                continue;
            }
            if bound.iter().any(|(i, _)| *i == index) {
                let pname = f.param_name(index).unwrap_or_default();
                self.error("SFC0307", arg.span, format!("parameter `{pname}` is given twice"));
                bad = true;
                continue;
            }
            if let Some(v) = &arg.value {
                bound.push((index, v));
            }
        }
        if bad {
            self.check_args_loosely(args);
            return Type::Error;
        }
        let n = bound.len();
        let max_ok = f.extensible || n <= f.params.len();
        let missing: Vec<String> = (0..f.params.len())
            .filter(|i| !bound.iter().any(|(j, _)| j == i))
            .filter_map(|i| f.param_name(i))
            .collect();
        let gap = bound.iter().any(|(i, _)| *i >= f.params.len() && *i >= n);
        if !max_ok || !missing.is_empty() || gap {
            let msg = if args.iter().all(|a| a.name.is_none()) {
                let at_least = if f.extensible { "at least " } else { "" };
                format!(
                    "`{}` takes {at_least}{} argument{}, but {n} {} given",
                    f.name,
                    f.params.len(),
                    if f.params.len() == 1 { "" } else { "s" },
                    if n == 1 { "was" } else { "were" }
                )
            } else if !missing.is_empty() {
                let list: Vec<String> = missing.iter().map(|m| format!("`{m}`")).collect();
                format!("the call of `{}` is missing the input {}", f.name, list.join(", "))
            } else {
                format!("the inputs of `{}` must be numbered without gaps", f.name)
            };
            self.error("SFC0307", span, msg);
            self.check_args_loosely(args);
            return Type::Error;
        }
        bound.sort_by_key(|(i, _)| *i);
        let ret_same = f.ret == ReturnType::Same;
        let ops: Vec<(usize, Operand<'_>)> = bound
            .iter()
            .map(|(i, e)| {
                let hint = match f.param_type(*i) {
                    Some(ParamType::Fixed(t)) => Some(t.clone()),
                    Some(ParamType::Same(_)) if ret_same || f.operator.is_some() => expected.cloned(),
                    _ => None,
                };
                (*i, self.operand(e, hint.as_ref()))
            })
            .collect();
        self.std_apply(f, ops, span, expected)
    }

    /// Types a standard function applied to checked operands (index of the input, operand).
    pub(crate) fn std_apply(
        &mut self,
        f: &StdFunction,
        ops: Vec<(usize, Operand<'_>)>,
        span: Span,
        expected: Option<&Type>,
    ) -> Type {
        let what = format!("`{}`", f.name);
        if let Some(op) = f.operator {
            let ops: Vec<Operand<'_>> = ops.into_iter().map(|(_, o)| o).collect();
            return self.combine(op, ops, span, expected, &what);
        }
        // The `Same` inputs share one type: unify them like the operands of an operator.
        let mut same_class = None;
        let mut same_ops: Vec<Operand<'_>> = Vec::new();
        for (i, o) in ops {
            let pname = f.param_name(i).unwrap_or_default();
            match f.param_type(i) {
                Some(ParamType::Same(class)) => {
                    same_class = Some(*class);
                    same_ops.push(o);
                }
                Some(ParamType::Fixed(t)) => {
                    let ok = match (&o.ty, o.untyped) {
                        // CODESYS converts an integer argument to the input's integer type.
                        (Some(ty), _) if self.codesys && ty.is_integer() && t.is_integer() => true,
                        (Some(ty), _) => ty.assignable_to(t),
                        (None, Some(u)) => {
                            self.record(o.expr.span, t);
                            matches!(fit(u, t), Fit::Fits)
                        }
                        (None, None) => true,
                    };
                    if !ok {
                        let p = operand_phrase(self, &o);
                        self.error(
                            "SFC0302",
                            o.expr.span,
                            format!("type mismatch: input `{pname}` of {what} is `{t}`, but the argument is {p}"),
                        );
                    }
                }
                Some(ParamType::Any(class)) => {
                    let ok = match (&o.ty, o.untyped) {
                        (Some(ty), _) => class.admits(ty),
                        // An untyped constant fits when some member of the class holds it.
                        (None, Some(u)) => {
                            let holder = [Type::DInt, Type::LInt, Type::ULInt, Type::LReal, Type::DWord, Type::LWord]
                                .into_iter()
                                .find(|t| class.admits(t) && matches!(fit(u, t), Fit::Fits));
                            if let Some(t) = &holder {
                                self.record(o.expr.span, t);
                            }
                            holder.is_some()
                        }
                        (None, None) => true,
                    };
                    if !ok {
                        let p = operand_phrase(self, &o);
                        self.error(
                            "SFC0302",
                            o.expr.span,
                            format!(
                                "type mismatch: input `{pname}` of {what} is {}, but the argument is {p}",
                                class.name()
                            ),
                        );
                    }
                }
                None => {}
            }
        }
        let t_same = match same_class {
            Some(class) => {
                let hint = if f.ret == ReturnType::Same { expected } else { None };
                self.unify(&same_ops, class, hint, &what)
            }
            None => Type::Error,
        };
        match &f.ret {
            ReturnType::Fixed(t) => t.clone(),
            ReturnType::Same => t_same,
            ReturnType::FromContext(class, default) => {
                expected.filter(|t| class.admits(t) && !t.is_error()).cloned().unwrap_or_else(|| default.clone())
            }
        }
    }
}

/// Describes an operand's type for a message.
pub(crate) fn operand_phrase(ck: &Checker<'_, '_>, o: &Operand<'_>) -> String {
    match &o.ty {
        Some(t) => ck.phrase(o.expr, t),
        None => untyped_phrase(o.untyped),
    }
}
