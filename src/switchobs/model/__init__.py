"""Models of the class dz/dt = s(y,t)(A z + d(y)) + b(y) u, y = C z; boxes of their parameters."""

from ._box import ParameterBox, model_terms, parse_box
from ._builtin import builtin_model, builtin_names, load_model
from ._expr import FUNCTIONS as EXPRESSION_FUNCTIONS
from ._expr import exact_number, free_names, parse_expression
from ._interop import entries, is_statespace, matrix_rows, statespace_matrices, user_matrix
from ._model import Model, make_symbol, numeric, rational_value, read_toml, symbols_from_json, symbols_to_json

__all__ = ["EXPRESSION_FUNCTIONS", "Model", "entries", "exact_number", "is_statespace", "matrix_rows",
           "statespace_matrices", "free_names", "builtin_model", "builtin_names", "load_model", "make_symbol", "numeric",
           "parse_expression", "rational_value", "read_toml", "symbols_to_json", "symbols_from_json",
           "ParameterBox", "model_terms", "parse_box", "user_matrix"]
