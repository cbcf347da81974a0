"""Alembic migrations of the gaitpref schema (run them with ``gaitpref db upgrade``)."""
