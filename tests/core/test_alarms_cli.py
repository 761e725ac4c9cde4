"""The alarm rules from the command line: list, check, dump, and --alarms on the desk."""

import io
import tomllib

import pytest

from app.cli import apply_flags, build_parser
from app.config import DeskConfig, load_config
from app.core.alarms import default_alarm_config, site_alarm_file, use_alarm_file
from app.core.alarms.cli import main


@pytest.fixture(autouse=True)
def _no_site_file():
    yield
    use_alarm_file(None)


def test_list_shows_every_rule(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    assert "gas_lel_pct" in out and "limit" in out and "rate" in out
    assert "flag.FAILSAFE_STOP" in out and "link.lost" in out and "flood guard" in out


def test_check_good_and_bad_files(tmp_path, capsys):
    good = tmp_path / "good.toml"
    good.write_text("[limit.temp_c]\nhigh = 50.0\n", encoding="utf-8")
    assert main(["--check", str(good)]) == 0
    assert "good.toml: ok" in capsys.readouterr().out
    bad = tmp_path / "bad.toml"
    bad.write_text("[limit.temp_c]\nhigh = 'x'\n", encoding="utf-8")
    assert main(["--check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.toml: [limit.temp_c] high: expected a number, got 'x'" in err


def test_dump_is_toml_with_the_override(tmp_path):
    f = tmp_path / "site.toml"
    f.write_text("[limit.temp_c]\nhigh = 52.5\n", encoding="utf-8")
    out = io.StringIO()
    assert main(["--file", str(f), "--dump"], out) == 0
    data = tomllib.loads(out.getvalue())
    assert data["limit"]["temp_c"]["high"] == 52.5 and data["limit"]["gas_lel_pct"]["high"] == 10


def test_desk_option_and_config_key(tmp_path):
    f = tmp_path / "site.toml"
    f.write_text("[limit.temp_c]\nhigh = 52.5\n[limit.gas_lel_pct]\nhigh = 'x'\n",
                 encoding="utf-8")
    cfg = DeskConfig()
    apply_flags(cfg, build_parser().parse_args(["--demo", "--alarms", str(f)]))
    assert cfg.alarms_file == str(f)
    conf = tmp_path / "desk.toml"
    conf.write_text(f'alarms_file = "{f}"\n', encoding="utf-8")
    assert load_config(conf).alarms_file == str(f)
    problems = use_alarm_file(cfg.alarms_file)
    assert len(problems) == 1 and "[limit.gas_lel_pct] high" in problems[0]
    assert site_alarm_file() == f
    d = default_alarm_config()  # what the desk's models and session now start from
    assert d.limit("temp_c").high == 52.5 and d.limit("gas_lel_pct").high == 10.0
    use_alarm_file(None)
    assert default_alarm_config().limit("temp_c").high == 45.0


def test_bump_test_and_calibration_are_recorded_and_listed(tmp_path, capsys):
    f = str(tmp_path / "gas_service.json")
    t = 1_800_000_000.0
    assert main(["bump-test", "--gas", "ch4", "--result", "pass", "--by", "Ana",
                 "--file", f]) == 0
    assert "bump-test of CH4 recorded (pass, by Ana" in capsys.readouterr().out
    from app.core.alarms.cli import service_main
    assert service_main(["calibration", "--gas", "CH4", "--result", "fail", "--by", "Ben",
                         "--file", f], now=t) == 0
    capsys.readouterr()
    assert main(["service", "--file", f]) == 0
    out = capsys.readouterr().out
    assert "bump         CH4    pass   Ana" in out and "calibration  CH4    fail   Ben" in out
    assert "ok   gas.CH4.bump_overdue" in out
    assert "DUE  Gas CH4: last calibration failed" in out


def test_a_record_without_who_is_refused(tmp_path, capsys):
    f = tmp_path / "gas_service.json"
    assert main(["bump-test", "--gas", "CH4", "--result", "pass", "--by", " ",
                 "--file", str(f)]) == 2
    assert "who did it (--by) is required" in capsys.readouterr().err
    assert not f.exists()
