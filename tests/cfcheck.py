"""The two CF checkers, run on a result file where they are installed (neither is a dependency:
`pip install cfchecker compliance-checker`, and cfchecker needs the udunits2 C library, e.g.
`apt-get install libudunits2-0`); tests skip where they are not.

- cfchecker (NCAS, the CF community's checker), version 4.1 knows CF up to 1.8 and reads our
  `Conventions = CF-1.10` as no CF at all, so it checks a copy labelled CF-1.8 against the 1.8
  rules. It downloads its standard-name, area-type and region tables unless given them; the files
  use none of the three, so it gets empty tables offline: any use would be an error.
- IOOS compliance-checker, suite cf:1.10, strict criteria (recommendations count as failures).
"""
import json
import shutil

import pytest

EMPTY_TABLE = '<?xml version="1.0"?><table><version_number>0</version_number>{}</table>'


def cfchecker_messages(path, tmp_path):
    """{'ERROR': [...], 'WARN': [...]} of cfchecker over the file's globals and variables."""
    cfchecks = pytest.importorskip("cfchecker.cfchecks")
    netCDF4 = pytest.importorskip("netCDF4")
    tables = {}
    for name, date_tag in (("standard_names", "<last_modified>none</last_modified>"),
                           ("area_types", "<date>none</date>"), ("region_names", "<date>none</date>")):
        tables[name] = tmp_path / f"{name}.xml"
        tables[name].write_text(EMPTY_TABLE.format(date_tag))
    copy = tmp_path / "cf18.nc"
    shutil.copyfile(path, copy)
    with netCDF4.Dataset(copy, "a") as nc:
        assert nc.Conventions == "CF-1.10"
        nc.Conventions = "CF-1.8"
    checker = cfchecks.CFChecker(version="1.8", silent=True, cfStandardNamesXML=str(tables["standard_names"]),
                                 cfAreaTypesXML=str(tables["area_types"]), cfRegionNamesXML=str(tables["region_names"]))
    result = checker.checker(str(copy))
    out = {kind: list(result["global"][kind]) for kind in ("FATAL", "ERROR", "WARN")}
    for name, messages in result["variables"].items():
        for kind in ("FATAL", "ERROR", "WARN"):
            out[kind] += [f"{name}: {m}" for m in messages[kind]]
    return out


def ioos_failures(path, tmp_path):
    """The failed checks of the IOOS compliance-checker's cf:1.10 suite, strict, as text."""
    runner = pytest.importorskip("compliance_checker.runner")
    suite = runner.CheckSuite()
    suite.load_all_available_checkers()
    report = tmp_path / "ioos.json"
    passed, errors = runner.ComplianceChecker.run_checker(str(path), ["cf:1.10"], 0, "strict",
                                                          output_filename=str(report), output_format="json")
    found = json.loads(report.read_text())["cf:1.10"]
    failures = [f"{p['name']}: {m}" for key in ("high_priorities", "medium_priorities", "low_priorities")
                for p in found.get(key, []) for m in p.get("msgs", []) if p["value"][0] < p["value"][1]]
    assert not errors, "the checker itself failed on the file"
    return [] if passed else failures or ["failed, no message"]
