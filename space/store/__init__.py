"""The store: every space's state and changeset log in one on-disk Oxigraph database.

Two halves, with a seam between them that a replicated log plugs into
(docs/store.md, "The seam"):

1. Decide and order a changeset: `state.SpaceState.decide` turns a checked
   request (`intake.WriteRequest`) into the net changeset it makes, with the
   next sequence number, as a `db_layout.Entry` (triples, log payload, request id).
   Embedded, the order is the store's writer thread and the log is Oxigraph's
   own `log:<space>` graph.
2. Apply an ordered changeset: `db.StoreDB.commit` writes a batch of entries,
   each with its log entry and seq, in one atomic SPARQL UPDATE; the server
   acknowledges only after it, then `publish.Publisher` publishes.

A replicated log takes the place of half 1's ordering: each replica installs
the log's entries in its order (`SpaceState.install(wire, payload)` → `Entry`), and
commits and publishes them exactly as above; a retried request is answered from
`StoreDB.outcome(space, request_id)` in both cases.
"""
