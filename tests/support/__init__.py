"""Helpers shared by several test files: model builders, constants and checks that are not fixtures (those
are in tests/conftest.py). Imported as ``support`` (``from support.sphere import sphere_model``): pytest puts
tests/ on ``sys.path`` for the test files there (its default "prepend" import mode, tests/ being no
package); a child process a test starts adds tests/ itself. No module here is a test module, and this
package imports nothing: each module imports only what it needs (``support.sphere`` loads DOLFINx)."""
