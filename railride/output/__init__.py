"""Files and tables of results, and the HTML report."""
