"""What the robot application ships: rules, ontologies and launch files (package data).

The folders are the top-level `rules/`, `ontology/` and `deploy/` of the project,
linked here so that a wheel carries them; read them with `agents.resources`.
"""
