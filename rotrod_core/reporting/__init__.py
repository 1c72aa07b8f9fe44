"""Above the physics: report, figures, paper facts, recordings, output.

- report: the text report
- figures: matplotlib figures
- facts: the paper's claims checked
- reproduce: rotrod reproduce
- analyze: rotrod analyze
- output: output directories and progress
- recording: Rerun recordings
- bag: rosbag2 (MCAP) files of offline runs, as the simulator node publishes them
- rig_comparison: the real rig beside the idealisation
"""
