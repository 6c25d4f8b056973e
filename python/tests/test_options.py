"""The options of identify() and select() come from the library's option table, which the
command line reads too:

- the signatures and the docstrings list every option of the table, runs and shard_size too,
  and a keyword that is not an option raises TypeError;
- a value is checked as the command line checks its text, the message naming the keyword;
- the options that name the model's variables are read against the model that the columns of
  states' derivatives complete, as on the command line.
"""

import inspect
import json

import pytest

import momentid
from momentid import _momentid

from conftest import DUFFING


@pytest.mark.parametrize("command", ["identify", "select"])
def test_the_signature_and_the_help_list_every_option_of_the_table(command):
    table = _momentid._options(command)
    function = getattr(momentid, command)
    parameters = inspect.signature(function).parameters
    keywords = [option["keyword"] for option in table]
    assert [p for p in parameters if parameters[p].kind == inspect.Parameter.KEYWORD_ONLY] == \
        keywords
    for option in table:
        assert f"{option['keyword']} (" in function.__doc__
        assert option["flag"] == "--" + option["keyword"].replace("_", "-")
    assert {"runs", "shard_size"} <= set(keywords)


def test_the_table_gives_each_command_its_own_options():
    identify = {o["keyword"] for o in _momentid._options("identify")}
    select = {o["keyword"] for o in _momentid._options("select")}
    assert {"multipliers", "degree", "method", "weighting", "extrapolate"} <= identify - select
    assert select - identify == {"exhaustive", "ranked", "validate"}


def test_an_unknown_keyword_is_a_type_error(duffing, record):
    with pytest.raises(TypeError, match=r"identify\(\) got an unexpected keyword argument 'lag'"):
        momentid.identify(duffing, record, lag=(3, 40))
    with pytest.raises(TypeError, match=r"select\(\) got an unexpected keyword argument 'degree'"):
        momentid.select(duffing, record, degree=3)


def test_values_are_checked_as_the_command_line_checks_them(duffing, record, cli_csv):
    with pytest.raises(momentid.UsageError,
                       match=r"^shard_size: expected at least 1k \(1024 bytes\), found 10 bytes$"):
        momentid.identify(duffing, cli_csv, shard_size=10)
    with pytest.raises(momentid.UsageError,
                       match=r"^threads: expected a whole number from 0 to 1024, found '2000'$"):
        momentid.identify(duffing, record, threads=2000)
    with pytest.raises(momentid.UsageError, match=r"^lags: expected \(first, last\), found 3$"):
        momentid.identify(duffing, record, lags=3)
    with pytest.raises(momentid.UsageError, match=r"^lags excludes multipliers$"):
        momentid.identify(duffing, record, multipliers="y", lags=(3, 40))


def test_shard_size_cuts_a_file_as_the_command_line_does(duffing, cli, cli_csv):
    # Shards add their sums in another order: the same to rounding, and to the command line's
    # last bit with the same shards.
    whole = momentid.identify(duffing, cli_csv, weighting="ls")
    shards = momentid.identify(duffing, cli_csv, weighting="ls", shard_size="64k", threads=2)
    assert shards.estimates == pytest.approx(whole.estimates, rel=1e-12)
    expected = json.loads(cli("identify", DUFFING, cli_csv, "--weighting", "ls", "--shard-size",
                              "64k", "--threads", 2, "--format", "json"))
    assert shards.to_dict()["parameters"] == expected["parameters"]


def test_center_all_is_read_against_the_completed_model(cli, tmp_path):
    """`center="all"` names the column of v' that `columns` declares, as --center all does."""
    path = tmp_path / "accelerometer.csv"
    cli("simulate", DUFFING.parent / "duffing_accelerometer.mom", "--samples", 20000, "--seed", 7,
        "--input", "x=multisine:f1=0.1,f2=2,lines=10", "-o", path)
    expected = json.loads(cli("identify", DUFFING, path.name, "--columns", "v'=a", "--center",
                              "all", "--format", "json", cwd=tmp_path))
    result = momentid.identify(DUFFING, path, columns={"v'": "a"}, center="all")
    assert {**result.to_dict(), "data": path.name} == expected
