"""statics"""
