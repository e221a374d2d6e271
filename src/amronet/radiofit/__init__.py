"""Radio models calibrated on measured RSSI: ``amronet radio-fit``.

Load readings and anchors (:mod:`~amronet.radiofit.data`), fit log-distance and multi-wall laws by least squares
with bootstrap intervals and cross-validation over positions (:mod:`~amronet.radiofit.fit`), estimate the
shadowing's spread and correlation distance (:mod:`~amronet.radiofit.variogram`), weigh the receivers' floor
(:mod:`~amronet.radiofit.tobit`), and emit a scenario's ``radio:`` block that reproduces the fitted mean through
amronet's own link budget (:mod:`~amronet.radiofit.emit`).
"""

from amronet.radiofit.data import RadioFitError, Readings, link_geometry, load_readings
from amronet.radiofit.emit import predict_with_block, radio_block, set_lines
from amronet.radiofit.fit import FitOptions, ModelFit, RadioFit, fit_radio
from amronet.radiofit.report import fit_dict, fit_text
from amronet.radiofit.writing import write_fit

__all__ = ["FitOptions", "ModelFit", "RadioFit", "RadioFitError", "Readings", "fit_dict", "fit_radio", "fit_text",
           "link_geometry", "load_readings", "predict_with_block", "radio_block", "set_lines", "write_fit"]
