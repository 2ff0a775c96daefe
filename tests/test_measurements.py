"""Loading and validating measured illuminance files."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from radtree.errors import RadtreeError
from radtree.measurements import (
    MeasurementError,
    grid_mean,
    load_measured,
    load_measured_rows,
    normalise_time,
)

DATA = Path(__file__).resolve().parents[1] / "examples" / "mendoza-street" / "data"
MENDOZA_HOURS = ("10:30", "11:30", "12:30", "13:30", "14:30", "15:30", "16:30")


def write(tmp_path: Path, text: str, name: str = "m.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# --------------------------------------------------------------------------- shipped data


def test_mendoza_measured_file_loads_seven_hours():
    frame, shape = load_measured(DATA / "measured_vertical_illuminance.csv")
    assert shape.kind == "mean"
    assert shape.units == "lux"
    assert shape.n_hours == 7
    assert shape.times == MENDOZA_HOURS
    assert list(frame.columns) == ["time", "measured_lux"]
    assert list(frame["time"]) == list(MENDOZA_HOURS)
    assert frame["measured_lux"].mean() == pytest.approx(1398.29, abs=0.005)
    assert frame["measured_lux"].mean() == pytest.approx(9788 / 7)


def test_mendoza_rows_file_loads():
    rows = load_measured_rows(DATA / "measured_rows.csv")
    assert list(rows.columns) == ["row", "sensors", "measured_mean_lux"]
    assert list(rows["row"]) == ["higher", "intermediate", "lower"]
    assert list(rows["sensors"]) == [3, 2, 3]
    assert list(rows["measured_mean_lux"]) == [1407.0, 1369.0, 1409.0]


# --------------------------------------------------------------------------- shapes and units


def test_row_shape(tmp_path):
    path = write(tmp_path, "# Units: lux\ntime,row,lux\n10:30,higher,1200\n10:30,Lower,1100\n"
                           "9:30,higher,1000\n9:30,lower,900\n")
    frame, shape = load_measured(path)
    assert shape.kind == "row"
    assert shape.labels == ("higher", "lower")
    assert shape.times == ("09:30", "10:30")
    assert list(frame.columns) == ["time", "row", "measured_lux"]
    assert frame.to_dict("records")[0] == {"time": "09:30", "row": "higher", "measured_lux": 1000.0}


def test_sensor_shape_with_integer_ids_and_row_column(tmp_path):
    path = write(tmp_path, "# Units: lux\ntime,sensor,row,lux\n10:30,1,higher,1200\n"
                           "10:30,0,lower,1000\n")
    frame, shape = load_measured(path)
    assert shape.kind == "sensor"
    assert shape.labels == (0, 1)
    assert list(frame["sensor"]) == [0, 1]
    assert list(frame["row"]) == ["lower", "higher"]


def test_klux_from_header_is_converted(tmp_path):
    path = write(tmp_path, "# Vertical illuminance. Units: klux\ntime,measured_lux\n"
                           "10:30,1.157\n11:30,1.504\n")
    frame, shape = load_measured(path)
    assert shape.units == "klux"
    assert list(frame["measured_lux"]) == pytest.approx([1157.0, 1504.0])


def test_klux_from_argument_and_alias(tmp_path):
    path = write(tmp_path, "time,measured_lux\n10:30,1.157\n")
    frame, _ = load_measured(path, units="klux")
    assert frame["measured_lux"].iloc[0] == pytest.approx(1157.0)
    path2 = write(tmp_path, "# units: klx\ntime,measured_lux\n10:30,1.5\n", "k.csv")
    assert load_measured(path2)[0]["measured_lux"].iloc[0] == pytest.approx(1500.0)


def test_argument_agreeing_with_header_is_accepted(tmp_path):
    path = write(tmp_path, "# Units: lux\ntime,measured_lux\n10:30,1157\n")
    assert load_measured(path, units="lux")[1].units == "lux"


def test_normalise_time():
    assert normalise_time("9:30") == "09:30"
    assert normalise_time(" 16:30 ") == "16:30"
    for bad in ("10.5", "24:00", "10:61", "10:30:00", ""):
        with pytest.raises(RadtreeError, match="HH:MM"):
            normalise_time(bad)


# --------------------------------------------------------------------------- validation errors


@pytest.mark.parametrize(
    ("text", "line", "pattern"),
    [
        ("# Units: lux\ntime,value\n10:30,1\n", 2, "fit none of the accepted shapes"),
        ("# Units: lux\nrow,lux\nhigher,1\n", 2, "fit none of the accepted shapes"),
        ("# Units: lux\ntime,measured_lux\n10:30,1157\n10.30,1200\n", 4, "10.30.*HH:MM"),
        ("# Units: lux\ntime,measured_lux\n10:30,1157\n11:30,1\n10:30,1200\n", 5,
         r"duplicate entry for time 10:30 \(first on line 3\)"),
        ("# Units: lux\ntime,row,lux\n10:30,higher,1157\n10:30,HIGHER,1200\n", 4,
         "duplicate entry for time 10:30, row higher"),
        ("# Units: lux\ntime,measured_lux\n10:30,1157\n11:30,-5\n", 4, "negative value -5"),
        ("# Units: lux\ntime,measured_lux\n10:30,nan\n", 3, "NaN"),
        ("# Units: lux\ntime,measured_lux\n10:30,\n", 3, "empty value"),
        ("# Units: lux\ntime,measured_lux\n10:30,1 157\n", 3, "not a number"),
        ("# Units: lux\ntime,measured_lux\n10:30,inf\n", 3, "infinite"),
        ("# Units: lux\ntime,measured_lux\n10:30,1157,x\n", 3, "3 field"),
        ("# Units: lux\ntime,measured_lux\n10:30,250000\n", 3, "exceeds the plausible maximum"),
        ("# Units: klux\ntime,measured_lux\n10:30,1157\n", 3, "lux rather than klux"),
        ("# Units: lux\ntime,measured_lux\n10:30,1157\n11:30,0.504\n", 4,
         r"grid mean 0.504 lx at 11:30 .*klux"),
        ("# Units: lux\ntime,time,measured_lux\n10:30,10:30,1\n", 2, "repeated column"),
    ],
)
def test_validation_errors_name_file_and_line(tmp_path, text, line, pattern):
    path = write(tmp_path, text)
    with pytest.raises(MeasurementError, match=pattern) as info:
        load_measured(path)
    assert str(path) in str(info.value)
    assert f"line {line}:" in str(info.value)
    assert info.value.line == line
    assert isinstance(info.value, RadtreeError)


def test_missing_file_names_path(tmp_path):
    path = tmp_path / "nope.csv"
    with pytest.raises(MeasurementError, match="not found") as info:
        load_measured(path)
    assert str(path) in str(info.value)


def test_empty_and_header_only_files(tmp_path):
    with pytest.raises(MeasurementError, match="no header"):
        load_measured(write(tmp_path, "# Units: lux\n\n"))
    with pytest.raises(MeasurementError, match="line 2: no data rows"):
        load_measured(write(tmp_path, "# Units: lux\ntime,measured_lux\n", "h.csv"))


def test_units_missing_or_conflicting(tmp_path):
    with pytest.raises(MeasurementError, match="units not stated"):
        load_measured(write(tmp_path, "time,measured_lux\n10:30,1157\n"))
    with pytest.raises(MeasurementError, match="states units 'lux' but units='klux'"):
        load_measured(write(tmp_path, "# Units: lux\ntime,measured_lux\n10:30,1\n", "c.csv"),
                      units="klux")
    with pytest.raises(MeasurementError, match="conflicting units.*line 1: lux.*line 2: klux"):
        load_measured(write(tmp_path, "# Units: lux\n# Units: klux\ntime,measured_lux\n10:30,1\n",
                            "d.csv"))
    with pytest.raises(MeasurementError, match="not 'lux' or 'klux'"):
        load_measured(write(tmp_path, "time,measured_lux\n10:30,1157\n", "e.csv"), units="W/m2")


def test_low_grid_mean_over_several_lines_lists_them(tmp_path):
    path = write(tmp_path, "# Units: lux\ntime,row,lux\n10:30,higher,1.2\n10:30,lower,0.4\n")
    with pytest.raises(MeasurementError, match=r"at 10:30 \(lines 3, 4\).*klux"):
        load_measured(path)


def test_hour_missing_a_row_is_an_error(tmp_path):
    path = write(tmp_path, "# Units: lux\ntime,row,lux\n10:30,higher,1200\n10:30,lower,1100\n"
                           "11:30,higher,1300\n")
    with pytest.raises(MeasurementError, match="line 5: time 11:30 lacks row.*lower"):
        load_measured(path)


@pytest.mark.parametrize(
    ("text", "line", "pattern"),
    [
        ("# Units: lux\nrow,sensors,measured_mean_lux\nhigher,3,1407\nHigher,3,1400\n", 4,
         r"duplicate row 'higher' \(first on line 3\)"),
        ("# Units: lux\nrow,sensors,measured_mean_lux\nhigher,2.5,1407\n", 3, "whole number"),
        ("# Units: lux\nrow,sensors,measured_mean_lux\nhigher,0,1407\n", 3, "whole number"),
        ("# Units: lux\nrow,sensors,measured_mean_lux\nhigher,3,-1\n", 3, "negative"),
        ("# Units: lux\nrow,sensors,measured_mean_lux\nhigher,3,0.4\n", 3, "klux"),
        ("# Units: lux\nrow,sensors,measured_mean_lux\nhigher,3,\n", 3, "empty value"),
        ("# Units: lux\nrow,measured_mean_lux\nhigher,1407\n", 2, "missing column.*sensors"),
    ],
)
def test_rows_file_validation(tmp_path, text, line, pattern):
    path = write(tmp_path, text)
    with pytest.raises(MeasurementError, match=pattern) as info:
        load_measured_rows(path)
    assert f"{path}: line {line}:" in str(info.value)


def test_rows_file_klux(tmp_path):
    path = write(tmp_path, "# Units: klux\nrow,sensors,measured_mean_lux\nhigher,3,1.407\n")
    assert load_measured_rows(path)["measured_mean_lux"].iloc[0] == pytest.approx(1407.0)


# --------------------------------------------------------------------------- grid mean


def test_grid_mean_weights_rows_by_sensor_count(tmp_path):
    path = write(tmp_path, "# Units: lux\ntime,row,lux\n10:30,higher,1200\n10:30,lower,1000\n")
    frame, _ = load_measured(path)
    out = grid_mean(frame, {"higher": 3, "lower": 1})
    assert out.to_dict("records") == [{"time": "10:30", "measured_lux": (3 * 1200 + 1000) / 4}]
    with pytest.raises(RadtreeError, match="sensors_per_row"):
        grid_mean(frame)
    with pytest.raises(RadtreeError, match="no sensor count for measured row.*lower"):
        grid_mean(frame, {"higher": 3})


def test_grid_mean_of_sensors_and_of_means():
    sensors = pd.DataFrame({"time": ["10:30"] * 2 + ["11:30"] * 2, "sensor": [0, 1, 0, 1],
                            "measured_lux": [100.0, 300.0, 200.0, 400.0]})
    assert list(grid_mean(sensors)["measured_lux"]) == [200.0, 300.0]
    means = pd.DataFrame({"time": ["11:30", "10:30"], "measured_lux": [2.0, 1.0]})
    assert list(grid_mean(means)["time"]) == ["10:30", "11:30"]
    with pytest.raises(RadtreeError, match="repeat hour"):
        grid_mean(pd.DataFrame({"time": ["10:30", "10:30"], "measured_lux": [1.0, 2.0]}))


def test_mixed_sensor_ids_are_kept_as_text(tmp_path):
    path = write(tmp_path, "# Units: lux\ntime,sensor,lux\n10:30,2,1200\n10:30,s1,1000\n")
    frame, shape = load_measured(path)
    assert list(frame["sensor"]) == ["2", "s1"]
    assert shape.labels == ("2", "s1")


def test_grid_mean_rejects_missing_values_and_normalises_labels():
    with pytest.raises(RadtreeError, match="non-numeric values at 11:30"):
        grid_mean(pd.DataFrame({"time": ["10:30", "11:30"], "measured_lux": [1.0, None]}))
    rows = pd.DataFrame({"time": ["9:30", "09:30"], "row": ["Higher", "lower"],
                         "measured_lux": [200.0, 100.0]})
    out = grid_mean(rows, {"HIGHER": 1, "lower": 1})
    assert out.to_dict("records") == [{"time": "09:30", "measured_lux": 150.0}]
