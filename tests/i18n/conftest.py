import os

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import pytest  # noqa: E402


@pytest.fixture
def zh(qapp):
    """The desk in Simplified Chinese for one test; English again afterwards."""
    from app.i18n import install_language

    assert install_language("zh_CN", qapp) == "zh_CN"
    yield qapp
    install_language("en", qapp)
