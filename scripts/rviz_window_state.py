#!/usr/bin/python3
"""Prints the `QMainWindow State` of rviz/geofusion.rviz's window layout (rviz restores its docks
from it): the camera image (the "RGB" display's dock) over the Displays tree on the left, the map
panel ("GeoFusion map") alone on the right at full height, the 3D view between them. rviz names
each dock after its panel or display and its tool bar "Tools"; a Qt main window with the same
names, laid out so and saved, gives the state rviz reads (Qt's format, not rviz's).

  scripts/rviz_window_state.py [WIDTH HEIGHT]    (system Python with PyQt5; no display needed)"""
import os
import sys

os.environ.setdefault('QT_QPA_PLATFORM', 'offscreen')
from PyQt5 import QtCore, QtWidgets  # noqa: E402


def main():
    width, height = (int(v) for v in sys.argv[1:3]) if len(sys.argv) >= 3 else (1380, 980)
    app = QtWidgets.QApplication(sys.argv[:1])
    window = QtWidgets.QMainWindow()
    window.setCentralWidget(QtWidgets.QWidget())
    tools = window.addToolBar('Tools')
    tools.setObjectName('Tools')

    def dock(name, area, w, h):
        d = QtWidgets.QDockWidget(name, window)
        d.setObjectName(name)
        content = QtWidgets.QWidget()
        content.setMinimumSize(w, h)
        d.setWidget(content)
        window.addDockWidget(area, d)
        return d

    rgb = dock('RGB', QtCore.Qt.LeftDockWidgetArea, 330, 250)
    displays = dock('Displays', QtCore.Qt.LeftDockWidgetArea, 330, 300)
    panel = dock('GeoFusion map', QtCore.Qt.RightDockWidgetArea, 500, 700)
    window.splitDockWidget(rgb, displays, QtCore.Qt.Vertical)
    window.resize(width, height)
    window.show()
    app.processEvents()
    window.resizeDocks([rgb, displays], [260, height - 360], QtCore.Qt.Vertical)
    window.resizeDocks([rgb, panel], [330, 500], QtCore.Qt.Horizontal)
    app.processEvents()
    print(bytes(window.saveState().toHex()).decode())


if __name__ == '__main__':
    main()
