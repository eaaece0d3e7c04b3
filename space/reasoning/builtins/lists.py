"""Read RDF lists in the state: `listLength listEntry listContains listNotContains listEqual
listNotEqual`, as Jena's builtins of those names (entries compared by value)."""

from __future__ import annotations

from rdflib import RDF, XSD, Literal

from space.reasoning.builtins.base import Args, Builtin, Context


def members(ctx: Context, head: int | None) -> list[int] | None:
    """Return the entries of the well-formed list starting at `head`, or None."""
    first, rest, nil = (ctx.terms.find(t) for t in (RDF.first, RDF.rest, RDF.nil))
    spo = ctx.store.spo
    found: list[int] = []
    seen = set()
    node = head
    while node != nil:
        if node is None or node in seen or first is None or rest is None:
            return None
        seen.add(node)
        entries = spo.get(node, {})
        values, nexts = entries.get(first), entries.get(rest)
        if not values or not nexts:
            return None
        found.append(next(iter(values)))
        node = next(iter(nexts))
    return found


def _bind(args: Args, position: int, value: int) -> Args | None:
    if args[position] is None:
        return (*args[:position], value, *args[position + 1 :])
    return args if args[position] == value else None


class ListLength(Builtin):
    """Bind (or check) the second argument to the length of the list, an xsd:int."""

    name = "listLength"
    arity = (2, 2)

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({1})

    def run(self, ctx: Context, args: Args) -> Args | None:
        entries = members(ctx, args[0])
        if entries is None:
            return None
        length = ctx.terms.id(Literal(str(len(entries)), datatype=XSD.int))
        if args[1] is not None and args[1] != length:
            return args if ctx.terms.same_value(args[1], length) else None
        return _bind(args, 1, length)


class ListEntry(Builtin):
    """Bind (or check) the third argument to the list's entry at the index (from 0)."""

    name = "listEntry"
    arity = (3, 3)

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({2})

    def run(self, ctx: Context, args: Args) -> Args | None:
        entries = members(ctx, args[0])
        index = ctx.terms.term(args[1]) if args[1] is not None else None  # type: ignore[arg-type]
        value = index.value if isinstance(index, Literal) else None
        if entries is None or not isinstance(value, int) or not 0 <= value < len(entries):
            return None
        entry = entries[value]
        if args[2] is not None and args[2] != entry:
            return args if ctx.terms.same_value(args[2], entry) else None
        return _bind(args, 2, entry)


def _contains(ctx: Context, args: Args) -> bool | None:
    entries = members(ctx, args[0])
    if entries is None or args[1] is None:
        return None
    return any(ctx.terms.same_value(e, args[1]) for e in entries)


class ListContains(Builtin):
    """Accept when the list has an entry equal (by value) to the second argument."""

    name = "listContains"
    arity = (2, 2)

    def run(self, ctx: Context, args: Args) -> Args | None:
        return args if _contains(ctx, args) else None


class ListNotContains(Builtin):
    """Accept when the list has no entry equal (by value) to the second argument."""

    name = "listNotContains"
    arity = (2, 2)

    def run(self, ctx: Context, args: Args) -> Args | None:
        return args if _contains(ctx, args) is False else None


def _equal(ctx: Context, args: Args) -> bool | None:
    a, b = members(ctx, args[0]), members(ctx, args[1])
    if a is None or b is None:
        return None
    if len(a) != len(b):
        return False
    # As Jena: each entry of the first consumes one equal (by value) entry of the second, in
    # any order, so the lists are equal as multisets.
    rest = list(b)
    for x in a:
        hit = next((i for i, y in enumerate(rest) if ctx.terms.same_value(x, y)), None)
        if hit is None:
            return False
        del rest[hit]
    return True


class ListEqual(Builtin):
    """Accept when both lists have the same entries (by value), in any order, as Jena."""

    name = "listEqual"
    arity = (2, 2)

    def run(self, ctx: Context, args: Args) -> Args | None:
        return args if _equal(ctx, args) else None


class ListNotEqual(Builtin):
    """Accept when both are lists and their entries differ."""

    name = "listNotEqual"
    arity = (2, 2)

    def run(self, ctx: Context, args: Args) -> Args | None:
        return args if _equal(ctx, args) is False else None


BUILTINS: tuple[Builtin, ...] = (
    ListLength(),
    ListEntry(),
    ListContains(),
    ListNotContains(),
    ListEqual(),
    ListNotEqual(),
)
