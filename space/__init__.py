"""tspace: a distributed triple space on Eclipse Zenoh.

This list is the library's API: an application (the robot's agents under
`agents/`) imports from here and from `space.reasoning`, nothing deeper.
"""

from __future__ import annotations

import importlib

# Where each name lives (as `name` or `name=attribute`). Imported on first use
# (PEP 562), so `import space.reasoning` loads the engine without the Zenoh
# side, and a process pays for the parts of the API it touches.
_HOMES = {
    "space._display": ("triple_text",),
    "space._stopping": ("on_stop_signals",),
    "space._heap": ("freeze_startup", "refreeze"),
    "space._paths": ("default_data_dir",),
    "space._ports": ("any_free_port", "probe_port=probe"),
    "space._request": ("Pending",),
    "space._session": ("check_can_listen",),
    "space._subscription": ("Change", "Subscription"),
    "space._turtle": ("read_turtle",),
    "space.ack": ("Ack", "Dropped"),
    "space.changeset": ("Changeset",),
    "space.cli.options": ("add_connect", "identity_of"),
    "space.client": ("Transaction", "TripleSpace"),
    "space.cluster_status": ("ClusterWatch",),
    "space.errors": (
        "ChangesetRejected",
        "InputError",
        "MalformedPayload",
        "NoQuorum",
        "NoReasoner",
        "NotApplied",
        "QueryError",
        "QueryTimeLimit",
        "SpaceError",
        "SpaceTimeout",
        "SpaceUnavailable",
        "TemplateError",
    ),
    "space.explanation": ("Explanation", "Written"),
    "space.functional": ("Replacement", "declares_functional", "replace_functional"),
    "space.identity": ("Identity", "load_identity"),
    "space.keys": ("KEY_ROOT=ROOT", "escape_key_chunk=escape", "unescape_key_chunk=unescape"),
    "space.lifespan": ("EXPIRY_AGENT", "check_lifespan"),
    "space.mirror": ("ChangeRecord", "MirrorReads=Reads", "SpaceMirror"),
    "space.prefixes": ("PrefixMap",),
    "space.presence": ("alive_agents", "declare_agent", "watch_agents"),
    "space.template": ("Template",),
    "space.terms": (
        "TextTriple",
        "Triple",
        "from_nt",
        "literal_nt",
        "text_of",
        "to_nt",
        "triple_from_nt",
        "triple_to_nt",
    ),
    "space.why": ("WhyService",),
    "space.zconfig": ("DEFAULT_ENDPOINT", "SECURE_ENDPOINT", "make_config"),
}
_WHERE = {
    name: (module, attribute or name)
    for module, names in _HOMES.items()
    for name, _, attribute in (entry.partition("=") for entry in names)
}


def __getattr__(name: str) -> object:
    """Import an API name's module on first use, and keep the name here."""
    try:
        module, attribute = _WHERE[name]
    except KeyError:
        raise AttributeError(f"module 'space' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), attribute)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


__all__ = [
    "DEFAULT_ENDPOINT",
    "EXPIRY_AGENT",
    "KEY_ROOT",
    "SECURE_ENDPOINT",
    "Ack",
    "Change",
    "ChangeRecord",
    "Changeset",
    "ChangesetRejected",
    "ClusterWatch",
    "Dropped",
    "Explanation",
    "Identity",
    "InputError",
    "MalformedPayload",
    "MirrorReads",
    "NoQuorum",
    "NoReasoner",
    "NotApplied",
    "Pending",
    "PrefixMap",
    "QueryError",
    "QueryTimeLimit",
    "Replacement",
    "SpaceError",
    "SpaceMirror",
    "SpaceTimeout",
    "SpaceUnavailable",
    "Subscription",
    "Template",
    "TemplateError",
    "TextTriple",
    "Transaction",
    "Triple",
    "TripleSpace",
    "WhyService",
    "Written",
    "add_connect",
    "alive_agents",
    "any_free_port",
    "check_can_listen",
    "check_lifespan",
    "declare_agent",
    "declares_functional",
    "default_data_dir",
    "escape_key_chunk",
    "freeze_startup",
    "from_nt",
    "identity_of",
    "literal_nt",
    "load_identity",
    "make_config",
    "on_stop_signals",
    "probe_port",
    "read_turtle",
    "refreeze",
    "replace_functional",
    "text_of",
    "to_nt",
    "triple_from_nt",
    "triple_text",
    "triple_to_nt",
    "unescape_key_chunk",
    "watch_agents",
]
