import pytest

from shadowhound.config import ConfigError, available_profiles, load_config


def test_offline_profile_is_the_default():
    cfg = load_config(environ={})
    assert cfg.backend == "offline" and cfg.robot.type == "sim" and cfg.profile == "offline"
    assert cfg.safety.max_linear_speed == 0.5 and cfg.safety.max_angular_speed == 1.0
    assert "offline" in available_profiles()


def test_environment_overrides_profile_and_options_override_environment():
    env = {
        "SHADOWHOUND_SAFETY__MAX_LINEAR_SPEED": "0.3",
        "SHADOWHOUND_SIM__TIME_SCALE": "1",
        "SHADOWHOUND_PLACES": "{lab: [1, 2]}",
        "UNRELATED": "x",
    }
    cfg = load_config("offline", environ=env)
    assert cfg.safety.max_linear_speed == 0.3 and cfg.sim.time_scale == 1.0
    assert cfg.places["lab"] == (1.0, 2.0) and "kitchen" in cfg.places  # added, not replaced
    cfg = load_config("offline", {"safety": {"max_linear_speed": 0.2}}, environ=env)
    assert cfg.safety.max_linear_speed == 0.2


def test_an_empty_environment_variable_is_an_empty_setting_and_a_bad_one_is_named():
    """Issue 32: an empty SHADOWHOUND_SPEECH__API_KEY_ENV failed and blamed the YAML file. Empty
    is what `api_key_env: ""` is in a profile: no key is sent."""
    from shadowhound.hearing import Transcriber

    env = {"SHADOWHOUND_SPEECH__API_KEY_ENV": "", "OPENAI_API_KEY": "sk-not-sent-0123456789"}
    cfg = load_config("offline", environ=env)
    assert cfg.speech.api_key_env == "" and cfg.llm.api_key_env == "OPENAI_API_KEY"
    assert Transcriber(cfg.speech, environ=env)._key == ""
    with pytest.raises(ConfigError) as bad:
        load_config("offline", environ={"SHADOWHOUND_SAFETY__MAX_LINEAR_SPEED": "fast"})
    said = str(bad.value)
    assert "from the environment variable SHADOWHOUND_SAFETY__MAX_LINEAR_SPEED" in said, said
    assert "offline.yaml" not in said, said


def test_yaml_file_profile(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("safety: {geofence_radius: 3}\nplaces: {Living Room: [1, 1]}\n")
    cfg = load_config(str(path), environ={})
    assert cfg.safety.geofence_radius == 3 and cfg.profile == "mine"
    assert cfg.places == {"living room": (1.0, 1.0)}


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (
            "safety: {max_linear_speed: -1}",
            "safety.max_linear_speed: Input should be greater than 0",
        ),
        ("safety: {max_speed: 1}", "safety.max_speed: Extra inputs are not permitted"),
        ("backend: gpt5", "backend: Input should be 'offline'"),
        ("places: {kitchen: [1]}", "places: Value error, must be a pair"),
        ("- a\n- b", "must be a YAML mapping"),
        ("safety: [", "cannot read config"),
    ],
)
def test_bad_config_is_explained(tmp_path, content, message):
    path = tmp_path / "bad.yaml"
    path.write_text(content)
    with pytest.raises(ConfigError, match=message.replace("(", r"\(").replace("[", r"\[")):
        load_config(str(path), environ={})


def test_unknown_profile_lists_the_available_ones():
    with pytest.raises(ConfigError, match="unknown config profile 'nope'; available profiles: "):
        load_config("nope", environ={})
    with pytest.raises(ConfigError, match="does not exist"):
        load_config("/nonexistent/x.yaml", environ={})
