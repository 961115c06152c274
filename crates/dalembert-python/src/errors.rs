//! The package's exceptions: the same one-line messages as the command line.

use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};

create_exception!(
    dalembert,
    SceneError,
    PyValueError,
    "A scene that cannot be read, built or changed as asked; the message names the file, the line and the element at fault."
);
create_exception!(
    dalembert,
    IntegrationError,
    PyRuntimeError,
    "A run that stopped early. `time` is the time it reached and `run` holds every row computed before it stopped."
);
