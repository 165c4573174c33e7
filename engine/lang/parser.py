"""Recursive-descent parser for XABSL 2 files (§1.3), with error recovery.

The grammar reads as a list of ``_parse_<production>`` methods in the order of §1.3. A token the
grammar cannot accept raises :class:`_SyntaxError` at that token (so a missing ``;`` is reported
on the next token, as the original racc parser does); recovery points catch it:

* per state of an option (resume at the next ``[initial] [target] state``),
* per namespace item (resume after the next ``;``/``}`` at the namespace's brace depth),
* per agent declaration (resume at the next ``agent``).

One run therefore reports every syntax error of every file. Only the first error of a
recovery region is reported, so one mistake yields one diagnostic.

Doc comments (``/** */``) are tokens: where the grammar allows them (§1.3 note e) they attach
to the following node; anywhere else they are a syntax error, exactly like the original.
"""

from __future__ import annotations

import functools

from xabsl_studio.engine.errors import CompileError
from xabsl_studio.engine.lang import ast
from xabsl_studio.engine.lang.diagnostics import Diagnostics
from xabsl_studio.engine.lang.tokens import Token, TokenType, doc_text, tokenize
from xabsl_studio.engine.types import Span

#: Binary operators by precedence level, lowest first (§1.3 table; unary binds tightest).
BINARY_LEVELS: tuple[tuple[str, ...], ...] = (
    ("||",),
    ("&&",),
    ("<", ">", "<=", ">=", "==", "!="),
    ("+", "-"),
    ("*", "/", "%"),
)
#: Levels whose operators are non-associative (``a < b < c`` is a syntax error).
NONASSOC_LEVELS = frozenset({2})
#: The level of each binary operator.
_LEVEL_OF = {op: level for level, operators in enumerate(BINARY_LEVELS) for op in operators}
BUILTINS = frozenset({"state_time", "option_time", "action_done", "conflict"})
TYPE_KEYWORDS = frozenset({"float", "bool", "enum"})
IO_KEYWORDS = frozenset({"input", "output", "internal"})
STATE_START = frozenset({"initial", "target", "state"})


#: How deep decision trees (``if``/``else`` and braces, also of the common decision) may nest.
#: Deeper input fails at once with ``nesting-too-deep`` instead of recursing to Python's limit.
MAX_DECISION_DEPTH = 1000
#: How deep expressions (parentheses, unary operators, call arguments, ``?:``) may nest.
MAX_EXPRESSION_DEPTH = 1000


class _TooDeepError(CompileError):
    """Nesting beyond a limit: the rest of the file is not parsed (like a RecursionError)."""

    def __init__(self, token: Token, message: str) -> None:
        super().__init__(message)
        self.token = token
        self.message = message


class _SyntaxError(CompileError):
    def __init__(self, token: Token, message: str, code: str = "syntax-error") -> None:
        super().__init__(message)
        self.token = token
        self.message = message
        self.code = code


def parse_file(path: str, text: str, diagnostics: Diagnostics) -> ast.SourceFile:
    """Parse one file's text; problems are added to ``diagnostics``, never raised."""
    tokens = tokenize(text, path, diagnostics)
    truncated = any(d.code == "unterminated-comment" and d.file == path for d in diagnostics)
    parser = _Parser(path, text, tokens, diagnostics, truncated)
    try:
        return parser.parse()
    except _TooDeepError as deep:
        diagnostics.add("nesting-too-deep", deep.message, deep.token.span, path)
        return ast.SourceFile(path, text)
    except RecursionError:
        token = parser.tok
        diagnostics.add(
            "nesting-too-deep", "expressions or decision trees nest too deeply to parse here", token.span, path
        )
        return ast.SourceFile(path, text)


class _Parser:
    def __init__(self, path: str, text: str, tokens: list[Token], diagnostics: Diagnostics, truncated: bool) -> None:
        self.path = path
        self.text = text
        self.tokens = tokens
        self.diagnostics = diagnostics
        self.truncated = truncated
        self.pos = 0
        #: the current token, ``tokens[pos]`` (kept by advance and seek: the parser reads it most)
        self.tok = tokens[0]
        #: current nesting of decision trees and of expressions (see the MAX_* limits)
        self.decision_depth = 0
        self.expression_depth = 0

    @functools.cached_property
    def depth(self) -> list[int]:
        """The brace depth before each token; recovery resumes at the depth it started from.

        Computed on the first syntax error only: a file without errors never needs it.
        """
        depths: list[int] = []
        depth = 0
        for token in self.tokens:
            depths.append(depth)
            if token.text == "{":
                depth += 1
            elif token.text == "}":
                depth = max(0, depth - 1)
        return depths

    # ---------------------------------------------------------------- token helpers

    # Operator tests compare the text only (`tok.text == ";"`): no other kind of token can have
    # an operator's text (strings keep their quotes, ranges their brackets, comments their
    # markers, and words and numbers start with a letter, `_`, `@` or a digit).

    def at(self, kind: TokenType) -> bool:
        """Whether the current token is of ``kind``.

        Unlike reading ``self.tok.type`` twice, a call is no narrowing that a type checker
        carries over an ``advance()`` in between.
        """
        return self.tok.type is kind

    def seek(self, pos: int) -> None:
        """Go back (or forth) to the token at ``pos``."""
        self.pos = pos
        self.tok = self.tokens[pos]

    def peek(self, offset: int = 1) -> Token:
        return self.tokens[min(self.pos + offset, len(self.tokens) - 1)]

    def advance(self) -> Token:
        token = self.tok
        if token.type is not TokenType.EOF:  # the list ends with EOF: pos + 1 exists
            self.pos += 1
            self.tok = self.tokens[self.pos]
        return token

    def error(self, expected: str, token: Token | None = None) -> _SyntaxError:
        token = token or self.tok
        if token.type is TokenType.EOF:
            return _SyntaxError(token, f"unexpected end of file; expected {expected}", "unexpected-end-of-file")
        if token.type is TokenType.DOC_COMMENT:
            return _SyntaxError(
                token,
                "syntax error: a doc comment is not allowed here (only before agent, namespace, "
                "const, symbol, enum, behavior, parameter, option, if and else)",
            )
        if token.type is TokenType.INITIAL_COMMENT:
            return _SyntaxError(token, "syntax error: a /*** title comment may only open a file")
        return _SyntaxError(token, f"syntax error: unexpected {token.describe()}; expected {expected}")

    def expect_op(self, text: str) -> Token:
        if not self.tok.is_op(text):
            raise self.error(f"'{text}'")
        return self.advance()

    def expect_kw(self, text: str) -> Token:
        if not self.tok.is_kw(text):
            raise self.error(f"'{text}'")
        return self.advance()

    def expect_ident(self, what: str = "a name") -> ast.Name:
        token = self.tok
        if token.type is not TokenType.IDENTIFIER:
            raise self.error(what)
        self.advance()
        return ast.Name(token.text, token.span)

    def expect_string(self, what: str = "a string") -> str:
        if self.tok.type is not TokenType.STRING:
            raise self.error(what)
        return self.advance().text[1:-1]

    def take_doc(self) -> str | None:
        if self.tok.type is TokenType.DOC_COMMENT:
            return doc_text(self.advance())
        return None

    def span_from(self, start: Span) -> Span:
        last = self.tokens[self.pos - 1] if self.pos > 0 else self.tok
        return start.to(last.span)

    def report(self, error: _SyntaxError) -> None:
        if error.token.type is TokenType.EOF and self.truncated:
            return  # the unterminated comment already explains the end of the tokens
        if any(
            d.code == "illegal-character"
            and d.span
            and d.span.line == error.token.span.line
            and d.span.start < error.token.span.start
            for d in self.diagnostics
            if d.file == self.path
        ):
            return  # a follow-up of the illegal character just skipped on this line
        self.diagnostics.add(error.code, error.message, error.token.span, self.path)

    # ---------------------------------------------------------------- file

    def parse(self) -> ast.SourceFile:
        source = ast.SourceFile(self.path, self.text)
        if self.tok.type is TokenType.INITIAL_COMMENT:
            source.title_comment = self.advance().text[4:-2]
        try:
            while self.tok.is_kw("include"):
                start = self.advance().span
                path = self.expect_string("a file name in quotes")
                self.expect_op(";")
                source.includes.append(ast.Include(path, self.span_from(start)))
            doc_start = self.pos
            doc = self.take_doc()
            if self.tok.is_kw("option"):
                source.option = self.parse_option(doc)
            elif self.tok.is_kw("namespace"):
                source.namespace = self.parse_namespace(doc)
            elif self.tok.is_kw("agent"):
                self.seek(doc_start)
                self.parse_agents(source)
            elif self.tok.type is not TokenType.EOF:
                raise self.error("'include', 'option', 'namespace' or 'agent'")
            if self.tok.type is not TokenType.EOF:
                raise self.error("end of file (a file holds one option, one namespace or the agents)")
        except _SyntaxError as error:
            self.report(error)
        return source

    # ---------------------------------------------------------------- agents

    def parse_agents(self, source: ast.SourceFile) -> None:
        while self.tok.type is not TokenType.EOF:
            try:
                doc = self.take_doc()
                start = self.expect_kw("agent").span
                name = self.expect_ident("the agent's name")
                self.expect_op("(")
                title = self.expect_string("the agent's title in quotes")
                self.expect_op(",")
                root = self.expect_ident("the root option's name")
                self.expect_op(")")
                self.expect_op(";")
                source.agents.append(ast.AgentDecl(name, title, root, self.span_from(start), doc))
            except _SyntaxError as error:
                self.report(error)
                self.advance()
                while not self.at(TokenType.EOF) and not self.tok.is_kw("agent"):
                    self.advance()
                # a doc comment right before the resumed agent belongs to it
                if self.pos > 0 and self.tokens[self.pos - 1].type is TokenType.DOC_COMMENT:
                    self.seek(self.pos - 1)

    # ---------------------------------------------------------------- namespaces

    def parse_namespace(self, doc: str | None) -> ast.Namespace:
        start = self.expect_kw("namespace").span
        name = self.expect_ident("the namespace's name")
        self.expect_op("(")
        title = self.expect_string("the namespace's title in quotes")
        self.expect_op(")")
        self.expect_op("{")
        body = self.pos
        items: list[ast.NamespaceItem] = []
        while self.tok.text != "}":
            if self.tok.type is TokenType.EOF:
                raise self.error("'}'")
            try:
                items.append(self.parse_namespace_item())
            except _SyntaxError as error:
                self.report(error)
                self.recover_to_item(self.depth[body])
        self.advance()
        return ast.Namespace(name, title, items, self.span_from(start), doc)

    def recover_to_item(self, depth: int) -> None:
        """Skip to just after a ``;`` or ``}`` at the namespace body's depth."""
        self.advance()
        while self.tok.type is not TokenType.EOF:
            previous = self.tokens[self.pos - 1]
            at_depth = self.depth[self.pos] == depth
            if at_depth and (previous.text == ";" or previous.text == "}"):
                if self.tok.text == ";":  # the ';' after an enum's '}'
                    self.advance()
                return
            if at_depth and self.tok.text == "}":
                return
            if self.depth[self.pos] < depth:
                return
            self.advance()

    def parse_namespace_item(self) -> ast.NamespaceItem:
        doc = self.take_doc()
        token = self.tok
        start = token.span
        if token.is_kw("behavior"):
            self.advance()
            name = self.expect_ident("the basic behavior's name")
            self.expect_op("{")
            params = []
            while self.tok.text != "}":
                params.append(self.parse_param_decl())
            self.advance()
            return ast.BehaviorDecl(name, params, self.span_from(start), doc)
        if token.is_kw("const") or (token.is_kw("float") and self.peek().is_kw("const")):
            if token.is_kw("float"):
                self.advance()
            self.expect_kw("const")
            name = self.expect_ident("the constant's name")
            self.expect_op("=")
            negative = False
            if self.tok.text == "-":
                self.advance()
                negative = True
            if self.tok.type is not TokenType.NUMBER:
                raise self.error("a number")
            text = self.advance().text
            unit = self.expect_string() if self.at(TokenType.STRING) else None
            self.expect_op(";")
            return ast.ConstDecl(name, text, negative, unit, self.span_from(start), doc)
        if token.is_kw("enum") and self.peek().type is TokenType.IDENTIFIER:
            # `enum E { .. };` and `enum E internal { .. };` declare enumerations, while
            # `enum E internal name;` declares an internal symbol of type E
            after = self.peek(2)
            if after.text == "{" or (after.is_kw("internal") and self.peek(3).is_op("{")):
                return self.parse_enum_decl(doc, start)
            if after.type is TokenType.KEYWORD and after.text in ("input", "output") and self.peek(3).is_op("{"):
                raise _SyntaxError(
                    after, "an enumeration can only be declared 'internal', not input or output", "enum-io"
                )
        return self.parse_symbol_decl(doc, start)

    def parse_enum_decl(self, doc: str | None, start: Span) -> ast.EnumDecl:
        self.expect_kw("enum")
        name = self.expect_ident("the enumeration's name")
        internal = False
        if self.tok.is_kw("internal"):
            self.advance()
            internal = True
        self.expect_op("{")
        elements = [self.expect_ident("an enum element")]
        while self.tok.text == ",":
            self.advance()
            elements.append(self.expect_ident("an enum element"))
        self.expect_op("}")
        self.expect_op(";")
        return ast.EnumDecl(name, internal, elements, self.span_from(start), doc)

    def parse_type(self) -> ast.TypeRef:
        token = self.tok
        if token.is_kw("float") or token.is_kw("bool"):
            self.advance()
            return ast.TypeRef("decimal" if token.text == "float" else "boolean", None, token.span)
        if token.is_kw("enum"):
            self.advance()
            enum = self.expect_ident("the enumeration's name")
            return ast.TypeRef("enum", enum, token.span.to(enum.span))
        return ast.TypeRef("decimal", None, None)

    def parse_symbol_decl(self, doc: str | None, start: Span) -> ast.SymbolDecl:
        type_ = self.parse_type()
        if not (self.tok.type is TokenType.KEYWORD and self.tok.text in IO_KEYWORDS):
            raise self.error("'input', 'output' or 'internal'")
        io = self.advance().text
        name = self.expect_ident("the symbol's name")
        range_, range_span, unit, unit_span = self.parse_range_unit()
        params = None
        if self.tok.text == "(":
            self.advance()
            params = []
            while self.tok.text != ")":
                params.append(self.parse_param_decl())
            self.advance()
        self.expect_op(";")
        return ast.SymbolDecl(type_, io, name, range_, unit, params, self.span_from(start), doc, range_span, unit_span)

    def parse_range_unit(self) -> tuple[str | None, Span | None, str | None, Span | None]:
        range_ = unit = None
        range_span = unit_span = None
        if self.tok.type is TokenType.RANGE:
            token = self.advance()
            range_, range_span = token.text[1:-1], token.span
        if self.tok.type is TokenType.STRING:
            token = self.advance()
            unit, unit_span = token.text[1:-1], token.span
        return range_, range_span, unit, unit_span

    def parse_param_decl(self) -> ast.ParamDecl:
        doc = self.take_doc()
        if doc is not None and self.tok.type is TokenType.KEYWORD and self.tok.text in STATE_START | {"common"}:
            raise _SyntaxError(
                self.tok,
                f"syntax error: unexpected keyword '{self.tok.text}' after a doc comment; doc comments "
                "are not allowed before states or common decisions (use a // comment)",
            )
        start = self.tok.span
        type_ = self.parse_type()
        name = self.expect_ident("a parameter name" if type_.span else "a parameter type or name")
        range_, range_span, unit, unit_span = self.parse_range_unit()
        self.expect_op(";")
        return ast.ParamDecl(type_, name, range_, unit, self.span_from(start), doc, range_span, unit_span)

    # ---------------------------------------------------------------- options

    def parse_option(self, doc: str | None) -> ast.OptionDecl:
        start = self.expect_kw("option").span
        name = self.expect_ident("the option's name")
        self.expect_op("{")
        body = self.pos
        params: list[ast.ParamDecl] = []
        common_decision = None
        common_action = None
        states: list[ast.StateDecl] = []
        try:
            while not self.tok.is_kw("common") and not (
                self.tok.type is TokenType.KEYWORD and self.tok.text in STATE_START
            ):
                params.append(self.parse_param_decl())
            if self.tok.is_kw("common") and self.peek().is_kw("decision"):
                common_decision = self.parse_common_decision()
            if self.tok.is_kw("common"):
                self.advance()
                self.expect_kw("action")
                common_action = self.parse_action_block()
            states.append(self.parse_state())
        except _SyntaxError as error:
            self.report(error)
            self.recover_to_state(self.depth[body])
        while self.tok.text != "}":
            if self.tok.type is TokenType.EOF:
                raise self.error("'}' closing the option")
            try:
                states.append(self.parse_state())
            except _SyntaxError as error:
                self.report(error)
                self.recover_to_state(self.depth[body])
        self.advance()
        return ast.OptionDecl(name, params, common_decision, common_action, states, self.span_from(start), doc)

    def recover_to_state(self, depth: int) -> None:
        """Skip to the next state header, or to the ``}`` closing the option."""
        self.advance()
        while self.tok.type is not TokenType.EOF:
            token = self.tok
            if token.type is TokenType.KEYWORD and token.text in STATE_START:
                return
            if token.text == "}" and self.depth[self.pos] == depth:
                return
            self.advance()

    def parse_common_decision(self) -> ast.CommonDecision:
        start = self.advance().span
        self.advance()  # 'decision'
        branches: list[ast.IfElse] = []
        if self.tok.text == "{":
            # the braces of `common decision { }` are no nesting level (as `decision { }`'s)
            self.advance()
            self.parse_cdtree(branches)
            self.expect_op("}")
        elif self.tok.is_kw("if") or self.tok.type is TokenType.DOC_COMMENT:
            self.parse_cdtree(branches)
        return ast.CommonDecision(branches, self.span_from(start))

    def parse_cdtree(self, branches: list[ast.IfElse]) -> None:
        """``cdtree ::= '{' cdtree '}' | [DOC] if (exp) dtree [[DOC] else cdtree]``."""
        self.enter_decision()
        try:
            self.parse_cdtree_level(branches)
        finally:
            self.decision_depth -= 1

    def enter_decision(self) -> None:
        self.decision_depth += 1
        if self.decision_depth > MAX_DECISION_DEPTH:
            raise _TooDeepError(
                self.tok,
                f"decision trees nest deeper than {MAX_DECISION_DEPTH} levels here; "
                "split the decision with a sub-option or flatten it with && and ||",
            )

    def parse_cdtree_level(self, branches: list[ast.IfElse]) -> None:
        if self.tok.text == "{":
            self.advance()
            self.parse_cdtree(branches)
            self.expect_op("}")
            return
        doc = self.take_doc()
        start = self.expect_kw("if").span
        self.expect_op("(")
        condition = self.parse_expression()
        self.expect_op(")")
        then = self.parse_dtree()
        branch = ast.IfElse(condition, then, None, self.span_from(start), doc)
        branches.append(branch)
        mark = self.pos
        else_doc = self.take_doc()
        if self.tok.is_kw("else"):
            self.advance()
            branch.else_doc = else_doc
            self.parse_cdtree(branches)
        else:
            self.seek(mark)

    def parse_dtree(self) -> ast.DTree:
        token = self.tok
        if token.is_kw("goto") or token.is_kw("stay"):
            return self.parse_dtree_level(token)
        self.enter_decision()
        try:
            return self.parse_dtree_level(token)
        finally:
            self.decision_depth -= 1

    def parse_dtree_level(self, token: Token) -> ast.DTree:
        if token.text == "{":
            self.advance()
            tree = self.parse_dtree()
            self.expect_op("}")
            return tree
        if token.is_kw("goto"):
            self.advance()
            target = self.expect_ident("a state name")
            self.expect_op(";")
            return ast.Goto(target, self.span_from(token.span))
        if token.is_kw("stay"):
            self.advance()
            self.expect_op(";")
            return ast.Stay(self.span_from(token.span))
        doc = self.take_doc()
        if not self.tok.is_kw("if"):
            raise self.error("'if', 'goto', 'stay' or '{'")
        start = self.advance().span
        self.expect_op("(")
        condition = self.parse_expression()
        self.expect_op(")")
        then = self.parse_dtree()
        else_doc = self.take_doc()
        self.expect_kw("else")
        otherwise = self.parse_dtree()
        return ast.IfElse(condition, then, otherwise, self.span_from(start), doc, else_doc)

    def parse_state(self) -> ast.StateDecl:
        start = self.tok.span
        initial = target = False
        if self.tok.is_kw("initial"):
            self.advance()
            initial = True
        if self.tok.is_kw("target"):
            self.advance()
            target = True
        self.expect_kw("state")
        name = self.expect_ident("the state's name")
        coop, count, given = "n", 0, False
        if self.tok.is_kw("capacity"):
            self.advance()
            if self.tok.type is not TokenType.NUMBER:
                raise self.error("the capacity (a number)")
            coop, count, given = "c", int(float(self.advance().text)), True
        elif self.tok.is_kw("synchronized"):
            self.advance()
            coop = "s"
            if self.tok.type is TokenType.NUMBER:
                count, given = int(float(self.advance().text)), True
        self.expect_op("{")
        decision = None
        leading_else = False
        decision_span = None
        if self.tok.is_kw("decision"):
            decision_span = self.advance().span
            self.expect_op("{")
            mark = self.pos
            doc = self.take_doc()
            if self.tok.is_kw("else"):
                self.advance()
                leading_else = True
                decision = self.parse_dtree()
                if isinstance(decision, ast.IfElse) and decision.doc is None:
                    decision.doc = doc
            else:
                self.seek(mark)
                decision = self.parse_dtree()
            self.expect_op("}")
        self.expect_kw("action")
        actions = self.parse_action_block()
        self.expect_op("}")
        return ast.StateDecl(
            name,
            initial,
            target,
            coop,
            count,
            decision,
            leading_else,
            decision_span,
            actions,
            self.span_from(start),
            given,
        )

    def parse_action_block(self) -> list[ast.ActionStmt]:
        self.expect_op("{")
        actions: list[ast.ActionStmt] = []
        while self.tok.text != "}":
            actions.append(self.parse_action())
        self.advance()
        return actions

    def parse_action(self) -> ast.ActionStmt:
        name = self.expect_ident("an output symbol, option or basic behavior")
        if self.tok.text == "=":
            self.advance()
            value = self.parse_expression()
            self.expect_op(";")
            return ast.Assign(name, value, self.span_from(name.span))
        explicit = None
        if self.tok.is_kw("option") or self.tok.is_kw("behavior"):
            explicit = self.advance().text
        if self.tok.text != "(":
            raise self.error("'=' or '('")
        args = self.parse_call_args()
        self.expect_op(";")
        return ast.CallAction(name, args, self.span_from(name.span), explicit)

    def parse_call_args(self) -> list[ast.CallArg]:
        self.expect_op("(")
        args: list[ast.CallArg] = []
        if self.tok.text != ")":
            while True:
                name = self.expect_ident("a parameter name")
                self.expect_op("=")
                value = self.parse_expression()
                args.append(ast.CallArg(name, value, self.span_from(name.span)))
                if self.tok.text != ",":
                    break
                self.advance()
        self.expect_op(")")
        return args

    # ---------------------------------------------------------------- expressions

    def parse_expression(self) -> ast.Expr:
        """``?:`` is non-associative: its else-branch may not itself be an unparenthesised ``?:``."""
        self.enter_expression()
        try:
            return self.parse_conditional()
        finally:
            self.expression_depth -= 1

    def enter_expression(self) -> None:
        self.expression_depth += 1
        if self.expression_depth > MAX_EXPRESSION_DEPTH:
            raise _TooDeepError(
                self.tok,
                f"expressions nest deeper than {MAX_EXPRESSION_DEPTH} levels here "
                "(parentheses, unary operators, calls)",
            )

    def parse_conditional(self) -> ast.Expr:
        condition = self.parse_binary(0)
        if self.tok.text != "?":
            return condition
        op = self.advance()
        then = self.parse_expression()
        self.expect_op(":")
        otherwise = self.parse_binary(0)
        if self.tok.text == "?":
            raise self.error("an operator or ')' (nested ?: needs parentheses)")
        return ast.CondOp(condition, then, otherwise, _expr_span(condition).to(_expr_span(otherwise)), op.span)

    def parse_binary(self, level: int) -> ast.Expr:
        """Binary operators of ``level`` and tighter, left-associative (precedence climbing).

        The same trees and errors as one recursive-descent function per level of
        :data:`BINARY_LEVELS`, without its six calls per operand (the parser's hottest path).
        """
        return self.climb(self.parse_unary(), level)

    def climb(self, left: ast.Expr, min_level: int) -> ast.Expr:
        """Extend ``left`` with the operators of ``min_level`` and tighter that follow it."""
        while True:
            token = self.tok
            if token.type is not TokenType.OPERATOR:
                return left
            level = _LEVEL_OF.get(token.text)
            if level is None or level < min_level:
                return left
            self.advance()
            # the right operand takes every operator that binds tighter than this one
            right = self.climb(self.parse_unary(), level + 1)
            left = ast.BinaryOp(token.text, left, right, _expr_span(left).to(_expr_span(right)), token.span)
            following = self.tok
            if (
                level in NONASSOC_LEVELS
                and following.type is TokenType.OPERATOR
                and _LEVEL_OF.get(following.text) == level
            ):
                raise self.error("an operator of another kind (comparisons do not chain)")

    def parse_unary(self) -> ast.Expr:
        token = self.tok
        if token.text == "-" or token.text == "!":
            self.advance()
            self.enter_expression()
            try:
                operand = self.parse_unary()
            finally:
                self.expression_depth -= 1
            return ast.UnaryOp(token.text, operand, token.span.to(_expr_span(operand)), token.span)
        return self.parse_primary()

    def parse_primary(self) -> ast.Expr:
        token = self.tok
        if token.type is TokenType.NUMBER:
            self.advance()
            return ast.NumberLit(token.text, token.span)
        if token.is_kw("true") or token.is_kw("false"):
            self.advance()
            return ast.BoolLit(token.text == "true", token.span)
        if token.type is TokenType.KEYWORD and token.text in BUILTINS:
            self.advance()
            return ast.Builtin(token.text, token.span)
        if token.type is TokenType.IDENTIFIER:
            self.advance()
            if self.tok.text == "(":
                args = self.parse_call_args()
                return ast.Call(ast.Name(token.text, token.span), args, self.span_from(token.span))
            return ast.Ident(token.text, token.span)
        if token.text == "(":
            self.advance()
            inner = self.parse_expression()
            self.expect_op(")")
            return ast.Paren(inner, self.span_from(token.span))
        raise self.error("an expression")


def _expr_span(expr: ast.Expr) -> Span:
    return expr.span


def parse_expression_text(text: str, path: str = "<expression>") -> ast.Expr:
    """Parse ``text`` as one XABSL expression (a decision's condition text); spans index ``text``.

    Raises:
        CompileError: ``text`` is not exactly one expression.
    """
    diagnostics = Diagnostics()
    tokens = tokenize(text, path, diagnostics)
    if diagnostics.errors:
        raise CompileError(diagnostics.errors[0].message)
    parser = _Parser(path, text, tokens, diagnostics, False)
    expr = parser.parse_expression()  # a syntax error raises (a CompileError)
    if parser.tok.type is not TokenType.EOF:
        raise CompileError(f"{path}: more than one expression in {text!r}")
    return expr
