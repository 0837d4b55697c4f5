"""The kit scenes/build.py makes clrender's scenes with: XML nodes and files (xmlnodes, files), meshes made in
code (geometry), scene objects (plugins), the camera model and checks; one module per scene family in
families/."""
