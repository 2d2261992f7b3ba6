"""coincli.standins: modules that stand in for others during one import, and only then."""

import subprocess
import sys
import types

import pytest

from coincli.standins import import_with_stand_ins, package_stand_in, standing_in


def test_stand_ins_are_there_only_within_the_block_and_never_replace_a_loaded_module():
    fake_json = types.ModuleType("json")
    fake = types.ModuleType("coincli_test_not_a_module")
    import json

    with standing_in({"json": fake_json, fake.__name__: fake}):
        assert sys.modules["json"] is json
        assert sys.modules[fake.__name__] is fake
    assert sys.modules["json"] is json
    assert fake.__name__ not in sys.modules
    with pytest.raises(RuntimeError), standing_in({fake.__name__: fake}):
        raise RuntimeError("an error inside")
    assert fake.__name__ not in sys.modules


def test_a_none_stand_in_hides_a_module_for_the_block_only(tmp_path, monkeypatch):
    (tmp_path / "coincli_test_hidden.py").write_text("VALUE = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with standing_in({"coincli_test_hidden": None}), pytest.raises(ImportError):
        import coincli_test_hidden  # noqa: F401
    import coincli_test_hidden

    assert coincli_test_hidden.VALUE == 1
    del sys.modules["coincli_test_hidden"]


def test_deferred_classes_import_their_module_when_first_used():
    """Calling the stand-in or reading its attributes is the real class's; nothing before."""
    script = ("import sys\n"
              "from coincli.standins import deferred_classes\n"
              "module = deferred_classes('fractions', 'Fraction')\n"
              "Fraction = module.Fraction\n"
              "annotation = Fraction | int\n"
              "assert 'fractions' not in sys.modules\n"
              "half = Fraction(1, 2)\n"
              "import fractions\n"
              "assert type(half) is fractions.Fraction and half == fractions.Fraction(1, 2)\n"
              "assert Fraction.from_float(0.5) == half\n"
              "assert not hasattr(Fraction, '__wrapped__')\n")
    subprocess.run([sys.executable, "-c", script], check=True, timeout=60)


def test_a_module_imports_once_under_its_stand_ins_and_its_names_are_real_afterwards(tmp_path):
    """What the target imports from a stood-in module is the stand-in's; the stand-in is gone
    after that import, and the target is loaded by its own loader."""
    (tmp_path / "stood.py").write_text("class Thing:\n"
                                       "    def __init__(self, value):\n"
                                       "        self.value = value\n"
                                       "    @classmethod\n"
                                       "    def name(cls):\n"
                                       "        return 'real'\n")
    (tmp_path / "target.py").write_text("from stood import Thing\n"
                                        "ANNOTATION = Thing | None\n"
                                        "def make():\n"
                                        "    return Thing(3)\n")
    script = ("import sys\n"
              "from coincli.standins import deferred_classes, import_with_stand_ins\n"
              "import_with_stand_ins('target', lambda: {'stood': deferred_classes("
              "'stood', 'Thing')})\n"
              "import target\n"
              "assert 'stood' not in sys.modules\n"
              "assert not any(type(f).__name__ == '_StandInFinder' for f in sys.meta_path)\n"
              "assert type(target.__loader__).__name__ == 'SourceFileLoader'\n"
              "assert target.__loader__ is target.__spec__.loader\n"
              "thing = target.make()\n"
              "import stood\n"
              "assert type(thing) is stood.Thing and thing.value == 3\n"
              "assert target.Thing.name() == 'real'\n")
    subprocess.run([sys.executable, "-c", script], check=True, timeout=60, cwd=tmp_path)


def test_nothing_stands_in_for_a_module_already_loaded():
    count = len(sys.meta_path)
    import_with_stand_ins("json", lambda: {})
    assert len(sys.meta_path) == count


def test_package_stand_in():
    stand_in = package_stand_in("email")
    assert stand_in.__path__ and stand_in.__spec__.name == "email"
    assert package_stand_in("json.decoder") is None  # a module, not a package
    assert package_stand_in("coincli_test_not_a_module") is None
