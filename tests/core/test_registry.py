"""The one registry of names (:mod:`roughbrdf.registry`): registration, aliases, lookups that
ignore case, ``_`` and spaces, did-you-mean hints, and names that are refused once taken; and the
registries built on it (models, distributions, shadowing) resolving names the same way.
"""

from __future__ import annotations

import pytest

import roughbrdf as rb
from roughbrdf.registry import Registry, canon, unknown_name


@pytest.fixture
def colours() -> Registry[int]:
    reg: Registry[int] = Registry("colour")
    reg.add("red", 1, aliases=("rouge", "Rot"))
    reg.add("light-blue", 2)
    return reg


# ------------------------------------------------------------------------------------------
# registration and lookup
# ------------------------------------------------------------------------------------------
def test_add_returns_the_entry_and_keeps_the_order(colours):
    assert colours.add("green", 3) == 3
    assert colours.names() == ["red", "light-blue", "green"]
    assert list(colours) == colours.names() and len(colours) == 3


def test_aliases_resolve_to_the_canonical_entry(colours):
    assert colours.get("rouge") == colours.get("rot") == colours.get("red") == 1
    assert colours.canonical("ROT") == "red"
    assert colours.aliases("red") == ["rouge", "rot"]
    assert colours.aliases("Rouge") == ["rouge", "rot"]      # asked by an alias: the same list
    assert colours.aliases("light-blue") == []


@pytest.mark.parametrize("typed", ["light-blue", "LIGHT-BLUE", "light_blue", "Light Blue",
                                   "  light-blue  "])
def test_lookups_ignore_case_underscores_and_spaces(colours, typed):
    assert colours.get(typed) == 2 and typed in colours
    assert colours.canonical(typed) == "light-blue"


def test_canon_is_the_lookup_key():
    assert canon(" Trowbridge_Reitz 1975 ") == "trowbridge-reitz-1975"
    assert canon(1975) == "1975"


def test_membership_of_unknown_names(colours):
    assert "blue" not in colours and "" not in colours


# ------------------------------------------------------------------------------------------
# unknown names: the message names them, lists the known ones and suggests close ones
# ------------------------------------------------------------------------------------------
def test_unknown_name_is_named_with_a_suggestion(colours):
    with pytest.raises(ValueError) as exc:
        colours.get("rde")
    assert str(exc.value) == "unknown colour 'rde'; did you mean 'red'? (known: red, light-blue)"


def test_a_close_alias_is_suggested_with_its_entry(colours):
    with pytest.raises(ValueError, match=r"did you mean 'rouge' \(red\)\?"):
        colours.canonical("rougee")


def test_no_suggestion_when_nothing_is_close(colours):
    with pytest.raises(ValueError) as exc:
        colours.get("zzzzzz")
    assert str(exc.value) == "unknown colour 'zzzzzz' (known: red, light-blue)"


def test_kind_with_a_placeholder_places_the_name():
    reg: Registry[int] = Registry("option {name} of the lamp")
    reg.add("on", 1)
    with pytest.raises(ValueError, match=r"^unknown option 'of' of the lamp; did you mean 'on'"):
        reg.get("of")


def test_unknown_name_helper_is_a_value_error():
    err = unknown_name("parameter", "ee", ["e", "n", "k"])
    assert isinstance(err, ValueError)
    assert str(err) == "unknown parameter 'ee'; did you mean 'e'? (known: e, n, k)"


def test_at_most_three_suggestions():
    reg: Registry[int] = Registry("thing")
    for i, name in enumerate(["abcd1", "abcd2", "abcd3", "abcd4", "abcd5"]):
        reg.add(name, i)
    with pytest.raises(ValueError) as exc:
        reg.get("abcd")
    hint = str(exc.value).split("did you mean ")[1].split("?")[0]
    assert len(hint.split(", ")) == 3


# ------------------------------------------------------------------------------------------
# a taken name is refused, and a refused registration adds nothing
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name, aliases, taken", [
    ("Red", (), "Red"), ("crimson", ("ROUGE",), "ROUGE"), ("rouge", (), "rouge"),
    ("crimson", ("light_blue",), "light_blue"),
])
def test_a_taken_name_or_alias_is_refused(colours, name, aliases, taken):
    before = (colours.names(), colours.aliases("red"), colours.aliases("light-blue"))
    with pytest.raises(ValueError) as exc:
        colours.add(name, 9, aliases=aliases)
    assert f"colour name {taken!r} is already taken by" in str(exc.value)
    assert (colours.names(), colours.aliases("red"), colours.aliases("light-blue")) == before
    assert name not in colours or colours.get(name) != 9


def test_a_refused_alias_list_registers_none_of_its_names(colours):
    with pytest.raises(ValueError, match="already taken by 'red'"):
        colours.add("crimson", 9, aliases=("scarlet", "rot"))
    assert "crimson" not in colours and "scarlet" not in colours


# ------------------------------------------------------------------------------------------
# the library's registries
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("registry, typed, canonical", [
    (lambda: rb.models.MODELS, "Torrance_Sparrow", "torrance-sparrow-1967"),
    (lambda: rb.models.MODELS, "RB08", "renhorn-boreman-2008"),
    (lambda: rb.distributions.DISTRIBUTIONS, "GGX", "trowbridge-reitz"),
])
def test_library_registries_resolve_aliases_in_any_case(registry, typed, canonical):
    assert registry().canonical(typed) == canonical


def test_a_model_registry_refuses_another_model_under_a_taken_alias():
    with pytest.raises(ValueError, match=r"model name 'TR75' is already taken by "
                                         r"'trowbridge-reitz-1975'"):
        rb.models.MODELS.add("my-model", type(rb.model("lambertian")), aliases=("TR75",))
    assert "my-model" not in rb.models.MODELS
