// regolith::Error and its subclasses as Python exceptions that keep the C++ message.
#include <regolith/core/Error.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/store/Import.hpp>

#include "Common.hpp"

#include <exception>

namespace regolith::python {

namespace {

/// A new exception class `regolith.<name>` deriving from `bases`; kept for the process's
/// life (the translator below refers to it after the module object is gone).
PyObject* newException(py::module_& m, const char* name, const py::tuple& bases, const char* doc) {
  const std::string qualified = std::string("regolith.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.add_object(name, py::handle(type));  // add_object takes its own reference
  return type;
}

}  // namespace

void bindErrors(py::module_& m) {
  static PyObject* const error = newException(
      m, "Error", py::make_tuple(py::handle(PyExc_RuntimeError)),
      "Base of every Regolith error (C++ regolith::Error); the message names the operation, "
      "the file and the field.");
  static PyObject* const invalid = newException(
      m, "InvalidArgument", py::make_tuple(py::handle(error), py::handle(PyExc_ValueError)),
      "An unusable argument: NaN coordinates, a bad size, a budget of 0 "
      "(regolith::InvalidArgument).");
  static PyObject* const domain = newException(
      m, "DomainError", py::make_tuple(py::handle(error), py::handle(PyExc_ValueError)),
      "A valid input with no finite answer, e.g. a wheel over nodata (regolith::DomainError).");
  static PyObject* const storeError = newException(
      m, "StoreError", py::make_tuple(py::handle(error), py::handle(PyExc_OSError)),
      "A store file is missing, unreadable, corrupt or lacks a grid (store::StoreError).");
  static PyObject* const ioError = newException(
      m, "IoError", py::make_tuple(py::handle(error), py::handle(PyExc_OSError)),
      "The file system refused a write: a folder that cannot be created, a full disk, a "
      "failed sync or rename (regolith::IoError).");
  static PyObject* const importError =
      newException(m, "RasterImportError", py::make_tuple(py::handle(storeError)),
                   "A raster GDAL cannot import as a DEM (store::ImportError).");
  static PyObject* const glError =
      newException(m, "GlError", py::make_tuple(py::handle(error)),
                   "No OpenGL 4.5 context, or a GL failure while rendering (clod::GlError).");

  // pybind11's translator type is void(*)(std::exception_ptr): the parameter must be by value.
  // NOLINTNEXTLINE(performance-unnecessary-value-param)
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const store::ImportError& e) {
      PyErr_SetString(importError, e.what());
    } catch (const store::StoreError& e) {
      PyErr_SetString(storeError, e.what());
    } catch (const IoError& e) {
      PyErr_SetString(ioError, e.what());
    } catch (const gl::GlError& e) {
      PyErr_SetString(glError, e.what());
    } catch (const InvalidArgument& e) {
      PyErr_SetString(invalid, e.what());
    } catch (const DomainError& e) {
      PyErr_SetString(domain, e.what());
    } catch (const regolith::Error& e) {
      PyErr_SetString(error, e.what());
    }
  });
}

}  // namespace regolith::python
