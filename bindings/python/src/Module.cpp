// The `regolith` Python module (docs/python.md).
#include "Common.hpp"

PYBIND11_MODULE(regolith, m) {
  m.doc() =
      "Regolith: planetary terrain stores, height and normal queries, import, generation, "
      "headless rendering and the rover traverse. Arrays in and out are numpy float64.";
  using namespace regolith::python;
  bindErrors(m);
  bindStore(m);
  bindQueries(m);
  bindCompose(m);
  bindRover(m);
  bindScene(m);
  bindSceneFile(m);
}
