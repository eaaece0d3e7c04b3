"""The HMI's web page (index.html, hmi.js, hmi.css) and the server that serves it."""
