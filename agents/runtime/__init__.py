"""The robot application's runtime: launch files, supervisor, `tspace up`, scenarios, live view."""
