"""Put on PYTHONPATH after a source tree by ``timing.tree_env``: the tree's own ``generated/``, ``templates/`` and
``scenes/`` then serve ``symmech.generated``, ``symmech.templates`` and ``symmech.scenes``. An editable install
maps those three packages to its own checkout whatever PYTHONPATH says, so a benchmark comparing two trees would
otherwise run one tree's symmech on the other's generated code."""
import importlib.util
import os
import sys

FOLDERS = {"symmech.generated": "generated", "symmech.templates": "templates", "symmech.scenes": "scenes"}


class TreeFolders:
    """A meta-path finder, first in line, for the three packages: the folder beside the imported symmech's."""

    @classmethod
    def find_spec(cls, name, path=None, target=None):
        if name not in FOLDERS or "symmech" not in sys.modules:
            return None
        tree = os.path.dirname(os.path.dirname(os.path.abspath(sys.modules["symmech"].__file__)))
        folder = os.path.join(tree, FOLDERS[name])
        if not os.path.isfile(os.path.join(folder, "__init__.py")):
            return None  # an installed symmech: the installer's mapping stands
        return importlib.util.spec_from_file_location(name, os.path.join(folder, "__init__.py"),
                                                      submodule_search_locations=[folder])


sys.meta_path.insert(0, TreeFolders)
