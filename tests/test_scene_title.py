"""Every scene kind takes a free-text `title` (the report's), and refuses a non-string one naming the field."""
import pytest

from badinput import bundled, edited
from symmech.core import registry, schema
from symmech.core.scene import SceneError

SCENES = {"grain": "grain_default", "impact": "impact_default", "trolley": "trolley_helix",
          "mechanism": "smm_double_pendulum"}


@pytest.mark.parametrize("kind", sorted(SCENES))
def test_title_in_every_kind(kind):
    data = edited(bundled(SCENES[kind]), ("title", "Design review 3: the ¾ scale"))
    assert data["kind"] == kind
    assert schema.validate(registry.get(kind).schema, data)["title"] == "Design review 3: the ¾ scale"
    with pytest.raises(SceneError) as info:
        schema.validate(registry.get(kind).schema, edited(data, ("title", 3)))
    assert info.value.field == "title"


def test_every_registered_kind_is_covered():
    assert sorted(registry.kinds()) == sorted(SCENES)
