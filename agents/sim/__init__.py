"""Simulated robot hardware: pure models the monitor agents drive, testable without a space."""
