"""The operator's desk: main window, panels and the Qt models behind them."""
