import subprocess
import sys


def test_import_is_light_and_exports_the_public_names():
    code = (
        "import sys\n"
        "from shadowhound import RobotAgent, MissionExecutor, MissionExecutorConfig, SimRobot, "
        "MockRobot\n"
        "heavy = [m for m in ('rclpy', 'fastapi', 'uvicorn', 'chromadb', 'torch', 'openai', "
        "'onnxruntime', 'numpy', 'mcp', 'mcp_types') if m in sys.modules]\n"
        "print(','.join(heavy))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == ""
